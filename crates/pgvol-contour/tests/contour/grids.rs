//! Building sampled fields for the tests.

use glam::Vec3;

/// A sampled field on a regular grid.
#[derive(Clone, Debug)]
pub struct Samples {
    pub values: Vec<f32>,
    pub dims: [usize; 3],
    pub origin: Vec3,
    pub spacing: f32,
}

impl Samples {
    /// Samples `f` at every node.
    pub fn from_fn(dims: [usize; 3], origin: Vec3, spacing: f32, f: impl Fn(Vec3) -> f32) -> Self {
        let mut values = Vec::with_capacity(dims.iter().product());
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    values.push(f(origin + spacing * Vec3::new(i as f32, j as f32, k as f32)));
                }
            }
        }
        Self {
            values,
            dims,
            origin,
            spacing,
        }
    }

    /// A unit-spaced grid whose nodes get `f(i, j, k)` inside and `border` on the outer layer.
    pub fn padded(dims: [usize; 3], border: f32, mut f: impl FnMut([usize; 3]) -> f32) -> Self {
        let mut values = Vec::with_capacity(dims.iter().product());
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    let n = [i, j, k];
                    let on_border = (0..3).any(|a| n[a] == 0 || n[a] + 1 == dims[a]);
                    values.push(if on_border { border } else { f(n) });
                }
            }
        }
        Self {
            values,
            dims,
            origin: Vec3::ZERO,
            spacing: 1.0,
        }
    }

    pub fn contour(&self, iso: f32) -> pgvol_core::Mesh {
        pgvol_contour::marching_cubes(&self.values, self.dims, self.origin, self.spacing, iso)
    }
}

/// A tiny deterministic generator so tests need no extra dependencies.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Self(seed ^ 0x9E37_79B9_7F4A_7C15)
    }

    pub fn next_u64(&mut self) -> u64 {
        // splitmix64
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[lo, hi)`.
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        let unit = (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32;
        lo + (hi - lo) * unit
    }
}

/// The 4x4x4 grid whose only non-border cell has inside corners `case`, corner `c` being node
/// `(1 + (c & 1), 1 + ((c >> 1) & 1), 1 + (c >> 2))`; `magnitude(c)` gives each corner's |value|.
pub fn single_cell(case: usize, mut magnitude: impl FnMut(usize) -> f32) -> Samples {
    Samples::padded([4, 4, 4], 1.0, |[i, j, k]| {
        let c = (i - 1) | ((j - 1) << 1) | ((k - 1) << 2);
        let m = magnitude(c);
        if (case >> c) & 1 == 1 {
            -m
        } else {
            m
        }
    })
}

/// An n³ checkerboard (inside where `i + j + k` has parity `inside_parity`): every face ambiguous.
pub fn checkerboard(n: usize, inside_parity: usize, mut magnitude: impl FnMut() -> f32) -> Samples {
    Samples::padded([n, n, n], 1.0, |[i, j, k]| {
        let m = magnitude();
        if (i + j + k) % 2 == inside_parity {
            -m
        } else {
            m
        }
    })
}

/// Node values for random fields: mostly ordinary, some exactly zero, NaN or extreme.
pub fn random_value() -> impl proptest::strategy::Strategy<Value = f32> {
    use proptest::prelude::*;
    prop_oneof![
        8 => -1.0f32..1.0,
        1 => Just(0.0f32),
        1 => Just(f32::NAN),
        1 => prop_oneof![Just(-1e-30f32), Just(1e-30f32), Just(-1e30f32)],
    ]
}

/// Random grids of 3 to 8 nodes a side, closed off by an outside border.
pub fn random_field() -> impl proptest::strategy::Strategy<Value = Samples> {
    use proptest::prelude::*;
    (3usize..9, 3usize..9, 3usize..9).prop_flat_map(|(x, y, z)| {
        prop::collection::vec(random_value(), x * y * z).prop_map(move |v| {
            let mut it = v.into_iter();
            Samples::padded([x, y, z], 1.0, |_| it.next().unwrap())
        })
    })
}
