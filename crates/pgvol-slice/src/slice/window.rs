//! The brick layers in reach of a run of layer planes: slabs loaded as the planes move up the
//! axis and dropped once below them, so only a window of the volume is held at a time.

use std::collections::BTreeMap;

use super::bricks::{BrickLayer, BrickSource};

pub(crate) struct Window<'s, S: BrickSource + ?Sized> {
    source: &'s S,
    axis: usize,
    /// Loaded slabs by number.
    slabs: BTreeMap<usize, Vec<BrickLayer<'s>>>,
}

impl<'s, S: BrickSource + ?Sized> Window<'s, S> {
    pub(crate) fn new(source: &'s S, axis: usize) -> Self {
        Window {
            source,
            axis,
            slabs: BTreeMap::new(),
        }
    }

    /// Holds exactly the slabs of `brick_layers`: loads the missing ones, drops the others.
    pub(crate) fn hold(&mut self, brick_layers: &[usize]) -> Result<(), S::Error> {
        let per = self.source.slab_bricks().max(1);
        let mut wanted: Vec<usize> = brick_layers.iter().map(|n| n / per).collect();
        wanted.sort_unstable();
        wanted.dedup();
        self.slabs.retain(|s, _| wanted.binary_search(s).is_ok());
        for s in wanted {
            if !self.slabs.contains_key(&s) {
                let layers = self.source.slab(self.axis, s)?;
                self.slabs.insert(s, layers);
            }
        }
        Ok(())
    }

    /// Brick layer `n`, which a call to [`Window::hold`] must have asked for.
    pub(crate) fn layer(&self, n: usize) -> &BrickLayer<'s> {
        let per = self.source.slab_bricks().max(1);
        &self.slabs[&(n / per)][n % per]
    }
}
