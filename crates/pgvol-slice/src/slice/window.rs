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

    /// Holds exactly the slabs of `brick_layers`: takes those of `loaded` ([`Window::load`]'s),
    /// loads the others missing, drops the rest.
    pub(crate) fn hold(
        &mut self,
        brick_layers: &[usize],
        loaded: Vec<(usize, Vec<BrickLayer<'s>>)>,
    ) -> Result<(), S::Error> {
        let wanted = self.slabs_of(brick_layers);
        self.slabs.retain(|s, _| wanted.binary_search(s).is_ok());
        for (s, layers) in loaded {
            if wanted.binary_search(&s).is_ok() {
                self.slabs.insert(s, layers);
            }
        }
        for s in wanted {
            if !self.slabs.contains_key(&s) {
                let layers = self.source.slab(self.axis, s)?;
                self.slabs.insert(s, layers);
            }
        }
        Ok(())
    }

    /// The slabs of `brick_layers` not held now.
    pub(crate) fn missing(&self, brick_layers: &[usize]) -> Vec<usize> {
        let mut wanted = self.slabs_of(brick_layers);
        wanted.retain(|s| !self.slabs.contains_key(s));
        wanted
    }

    /// Slabs `slabs` from the source, for a later [`Window::hold`]: loading them needs only a
    /// shared window, so it can run while the held slabs are read.
    pub(crate) fn load(
        &self,
        slabs: &[usize],
    ) -> Result<Vec<(usize, Vec<BrickLayer<'s>>)>, S::Error> {
        slabs
            .iter()
            .map(|&s| Ok((s, self.source.slab(self.axis, s)?)))
            .collect()
    }

    /// The slabs holding `brick_layers`, ascending and without repeats.
    fn slabs_of(&self, brick_layers: &[usize]) -> Vec<usize> {
        let per = self.source.slab_bricks().max(1);
        let mut wanted: Vec<usize> = brick_layers.iter().map(|n| n / per).collect();
        wanted.sort_unstable();
        wanted.dedup();
        wanted
    }

    /// Brick layer `n`, which a call to [`Window::hold`] must have asked for.
    pub(crate) fn layer(&self, n: usize) -> &BrickLayer<'s> {
        let per = self.source.slab_bricks().max(1);
        &self.slabs[&(n / per)][n % per]
    }
}
