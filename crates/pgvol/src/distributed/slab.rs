//! A box of grid bricks with the grid and basis they belong to, as compressed bytes: what
//! crosses between the parts of a distributed job and the process that splits and assembles it.

use std::ops::Range;

use glam::Vec3;
use pgvol_core::sparse::BrickValues;
use pgvol_core::{Background, Grid, SparseGrid, BRICK_NODES};
use pgvol_field::{Basis, CoefficientVolume};

use crate::error::{Error, ErrorKind, Result};

/// Identifies the bytes of a slab and their layout version.
const MAGIC: &[u8; 8] = b"PGVSLAB1";

/// zstd level for slabs in transit: level 1 compresses banded distances about as well as the
/// higher levels at a fraction of the time, and slabs are short-lived.
const ZSTD_LEVEL: i32 = 1;

/// Stored bricks and the sides of the absent ones over a box of bricks of a sparse grid.
#[derive(Clone, Debug, PartialEq)]
pub struct Slab {
    /// The whole grid the bricks belong to.
    pub grid: Grid,
    /// The basis of the coefficients, when the bricks are coefficients.
    pub basis: Basis,
    /// Values of absent bricks by side.
    pub background: Background,
    /// The box of bricks, per axis.
    pub bricks: [Range<usize>; 3],
    /// Runs `(start, length)` of inside bricks, in the box's brick order (x fastest).
    pub inside_runs: Vec<(u64, u64)>,
    /// Stored bricks of the box, in the order they are to be stored.
    pub stored: Vec<([usize; 3], Box<BrickValues>)>,
}

impl Slab {
    /// The bricks of `values` in the box `bricks`, stored ones in their stored order.
    pub fn cut(grid: Grid, basis: Basis, values: &SparseGrid, bricks: [Range<usize>; 3]) -> Slab {
        let counts = values.brick_counts();
        let bricks =
            [0, 1, 2].map(|a| bricks[a].start.min(counts[a])..bricks[a].end.min(counts[a]));
        let inside_runs = runs(&bricks, |b| values.is_inside(b));
        let inside_box = |b: &[usize; 3]| (0..3).all(|a| bricks[a].contains(&b[a]));
        let stored = values
            .stored()
            .filter(|(b, _)| inside_box(b))
            .map(|(b, v)| (b, Box::new(*v)))
            .collect();
        Slab {
            grid,
            basis,
            background: values.background(),
            bricks,
            inside_runs,
            stored,
        }
    }

    /// Applies the slab to `values`: sides first, then the stored bricks in order.
    pub fn apply(self, values: &mut SparseGrid) {
        self.apply_sides(values);
        for (b, v) in self.stored {
            values.insert(b, v);
        }
    }

    /// [`Slab::apply`] of the sides and of copies of the stored bricks `keep` names.
    pub fn apply_some(&self, values: &mut SparseGrid, keep: impl Fn([usize; 3]) -> bool) {
        self.apply_sides(values);
        for (b, v) in self.stored.iter().filter(|(b, _)| keep(*b)) {
            values.insert(*b, v.clone());
        }
    }

    /// Marks the slab's inside bricks in `values`.
    fn apply_sides(&self, values: &mut SparseGrid) {
        let [bx, by, _] = self.bricks.clone().map(|r| r.len());
        let lo = self.bricks.clone().map(|r| r.start);
        for (start, len) in &self.inside_runs {
            for flat in *start..start + len {
                let flat = flat as usize;
                let b = [
                    lo[0] + flat % bx,
                    lo[1] + (flat / bx) % by,
                    lo[2] + flat / (bx * by),
                ];
                values.set_inside(b, true);
            }
        }
    }

    /// A coefficient volume on the whole grid holding only this slab's bricks; every brick
    /// outside the box is absent and outside.
    pub fn volume(self) -> Result<CoefficientVolume> {
        let mut coeffs = SparseGrid::new(self.grid.dims, self.background);
        let (grid, basis) = (self.grid, self.basis);
        self.apply(&mut coeffs);
        CoefficientVolume::from_sparse(grid, basis, coeffs)
            .map_err(|e| Error::new(ErrorKind::Internal, format!("slab: {e}")))
    }

    /// The slab as compressed bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(128 + self.stored.len() * (12 + 4 * BRICK_NODES));
        out.extend_from_slice(MAGIC);
        let g = &self.grid;
        for v in [g.origin.x, g.origin.y, g.origin.z, g.spacing] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        for d in g.dims {
            out.extend_from_slice(&(d as u64).to_le_bytes());
        }
        let (tag, n, r) = match self.basis {
            Basis::Trilinear => (0u8, 0u8, 0.0f32),
            Basis::Bspline2 => (1, 0, 0.0),
            Basis::Bspline3 => (2, 0, 0.0),
            Basis::Pg { n, r } => (3, n, r),
        };
        out.extend_from_slice(&[tag, n]);
        out.extend_from_slice(&r.to_le_bytes());
        out.extend_from_slice(&self.background.outside.to_le_bytes());
        out.extend_from_slice(&self.background.inside.to_le_bytes());
        for r in &self.bricks {
            out.extend_from_slice(&(r.start as u64).to_le_bytes());
            out.extend_from_slice(&(r.end as u64).to_le_bytes());
        }
        out.extend_from_slice(&(self.inside_runs.len() as u64).to_le_bytes());
        for (s, l) in &self.inside_runs {
            out.extend_from_slice(&s.to_le_bytes());
            out.extend_from_slice(&l.to_le_bytes());
        }
        out.extend_from_slice(&(self.stored.len() as u64).to_le_bytes());
        for (b, v) in &self.stored {
            for c in b {
                out.extend_from_slice(&(*c as u32).to_le_bytes());
            }
            for x in v.iter() {
                out.extend_from_slice(&x.to_le_bytes());
            }
        }
        // Compressing a Vec in memory cannot fail.
        zstd::bulk::compress(&out, ZSTD_LEVEL).unwrap_or_default()
    }

    /// Reads the bytes of [`Slab::to_bytes`], checking every size against the bytes.
    pub fn from_bytes(bytes: &[u8]) -> Result<Slab> {
        let bad = |what: &str| {
            Error::new(
                ErrorKind::InputFile,
                format!("not a brick slab of a distributed job: {what}"),
            )
        };
        let raw = zstd::stream::decode_all(bytes).map_err(|_| bad("not zstd data"))?;
        let mut r = Reader { bytes: &raw, at: 0 };
        if r.take(8).ok_or_else(|| bad("too short"))? != MAGIC {
            return Err(bad("wrong magic"));
        }
        let f = |r: &mut Reader| r.f32().ok_or_else(|| bad("truncated header"));
        let origin = Vec3::new(f(&mut r)?, f(&mut r)?, f(&mut r)?);
        let spacing = f(&mut r)?;
        let mut dims = [0usize; 3];
        for d in &mut dims {
            *d = r.u64().ok_or_else(|| bad("truncated header"))? as usize;
        }
        let grid = Grid {
            origin,
            spacing,
            dims,
            offset: Default::default(),
        };
        let tag = r.take(2).ok_or_else(|| bad("truncated header"))?.to_vec();
        let pg_r = f(&mut r)?;
        let basis = match tag[0] {
            0 => Basis::Trilinear,
            1 => Basis::Bspline2,
            2 => Basis::Bspline3,
            3 => Basis::Pg { n: tag[1], r: pg_r },
            _ => return Err(bad("unknown basis")),
        };
        let background = Background {
            outside: f(&mut r)?,
            inside: f(&mut r)?,
        };
        if !(spacing.is_finite() && spacing > 0.0 && origin.is_finite())
            || dims.iter().any(|&d| !(2..=1 << 24).contains(&d))
        {
            return Err(bad("grid out of range"));
        }
        let counts = dims.map(|d| d.div_ceil(pgvol_core::BRICK_EDGE));
        let mut bricks = [0..0, 0..0, 0..0];
        for (a, range) in bricks.iter_mut().enumerate() {
            let s = r.u64().ok_or_else(|| bad("truncated box"))? as usize;
            let e = r.u64().ok_or_else(|| bad("truncated box"))? as usize;
            if s > e || e > counts[a] {
                return Err(bad("box outside the grid"));
            }
            *range = s..e;
        }
        let total = bricks.iter().map(|r| r.len() as u64).product::<u64>();
        let n_runs = r.u64().ok_or_else(|| bad("truncated runs"))?;
        if n_runs > (raw.len() as u64) / 16 {
            return Err(bad("more runs than bytes"));
        }
        let mut inside_runs = Vec::with_capacity(n_runs as usize);
        for _ in 0..n_runs {
            let s = r.u64().ok_or_else(|| bad("truncated runs"))?;
            let l = r.u64().ok_or_else(|| bad("truncated runs"))?;
            if s.checked_add(l).is_none_or(|e| e > total) {
                return Err(bad("run outside the box"));
            }
            inside_runs.push((s, l));
        }
        let n_stored = r.u64().ok_or_else(|| bad("truncated bricks"))?;
        let per = (12 + 4 * BRICK_NODES) as u64;
        if n_stored > (raw.len() as u64) / per {
            return Err(bad("more bricks than bytes"));
        }
        let mut stored = Vec::with_capacity(n_stored as usize);
        for _ in 0..n_stored {
            let mut b = [0usize; 3];
            for (a, c) in b.iter_mut().enumerate() {
                *c = r.u32().ok_or_else(|| bad("truncated brick"))? as usize;
                if !bricks[a].contains(c) {
                    return Err(bad("brick outside the box"));
                }
            }
            let mut v = Box::new([0.0f32; BRICK_NODES]);
            for x in v.iter_mut() {
                *x = r.f32().ok_or_else(|| bad("truncated brick"))?;
                if !x.is_finite() {
                    return Err(bad("value not finite"));
                }
            }
            stored.push((b, v));
        }
        Ok(Slab {
            grid,
            basis,
            background,
            bricks,
            inside_runs,
            stored,
        })
    }
}

/// Runs of bricks of `bricks` (x fastest) where `inside` holds.
fn runs(bricks: &[Range<usize>; 3], inside: impl Fn([usize; 3]) -> bool) -> Vec<(u64, u64)> {
    let mut out: Vec<(u64, u64)> = Vec::new();
    let mut flat = 0u64;
    for k in bricks[2].clone() {
        for j in bricks[1].clone() {
            for i in bricks[0].clone() {
                if inside([i, j, k]) {
                    match out.last_mut() {
                        Some((s, l)) if *s + *l == flat => *l += 1,
                        _ => out.push((flat, 1)),
                    }
                }
                flat += 1;
            }
        }
    }
    out
}

/// Little-endian fields from a byte slice.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take(&mut self, n: usize) -> Option<&[u8]> {
        let s = self.bytes.get(self.at..self.at.checked_add(n)?)?;
        self.at += n;
        Some(s)
    }
    fn u64(&mut self) -> Option<u64> {
        Some(u64::from_le_bytes(self.take(8)?.try_into().ok()?))
    }
    fn u32(&mut self) -> Option<u32> {
        Some(u32::from_le_bytes(self.take(4)?.try_into().ok()?))
    }
    fn f32(&mut self) -> Option<f32> {
        Some(f32::from_le_bytes(self.take(4)?.try_into().ok()?))
    }
}
