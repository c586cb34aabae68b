//! The 2D versions of pgvol's bases on a square grid, and fields made of them. Separable bases
//! reflect coefficients about the border nodes as pgvol's B-spline prefilter does; the radial
//! pseudo-Gaussian sees zero coefficients outside the grid, as in the paper.

use super::shapes::P2;
use pgvol_field::mirror;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Basis2 {
    Bilinear,
    Bspline2,
    Bspline3,
    /// `(1 − d²/r²)^(n+1)` for `d < r` (r in spacings): the paper's pg_n.
    Pg {
        n: u8,
        r: f64,
    },
}

impl Basis2 {
    pub fn label(self) -> String {
        match self {
            Basis2::Bilinear => "bilinear".into(),
            Basis2::Bspline2 => "bspline2".into(),
            Basis2::Bspline3 => "bspline3".into(),
            Basis2::Pg { n, r } => format!("pg-n{n}-r{r}"),
        }
    }

    /// How far (in spacings) a collocation point may move from its node and stay inside the
    /// node's support: per axis for separable bases, Euclidean for the radial one.
    pub fn reach(self) -> f64 {
        match self {
            Basis2::Bilinear => 1.0,
            Basis2::Bspline2 => 1.5,
            Basis2::Bspline3 => 2.0,
            Basis2::Pg { r, .. } => r,
        }
    }

    fn profile(self, x: f64) -> f64 {
        let a = x.abs();
        match self {
            Basis2::Bilinear => (1.0 - a).max(0.0),
            Basis2::Bspline2 if a < 0.5 => 0.75 - a * a,
            Basis2::Bspline2 if a < 1.5 => 0.5 * (1.5 - a).powi(2),
            Basis2::Bspline3 if a < 1.0 => 2.0 / 3.0 - a * a + 0.5 * a * a * a,
            Basis2::Bspline3 if a < 2.0 => (2.0 - a).powi(3) / 6.0,
            _ => 0.0,
        }
    }
}

/// A square grid of `n × n` nodes, node (i, j) at `origin + spacing · (i, j)`, index `i + n·j`.
#[derive(Clone, Copy, Debug)]
pub struct Grid2 {
    pub n: usize,
    pub origin: f64,
    pub spacing: f64,
}

impl Grid2 {
    pub fn len(&self) -> usize {
        self.n * self.n
    }
    pub fn node(&self, idx: usize) -> P2 {
        let (i, j) = (idx % self.n, idx / self.n);
        [
            self.origin + self.spacing * i as f64,
            self.origin + self.spacing * j as f64,
        ]
    }
    pub fn hi(&self) -> f64 {
        self.origin + self.spacing * (self.n - 1) as f64
    }
    pub fn contains(&self, p: P2) -> bool {
        p.iter().all(|&v| v >= self.origin && v <= self.hi())
    }
}

/// The nodes whose basis functions are non-zero at `p`, with their values (a node may appear
/// twice near the border for separable bases; the caller adds them up).
pub fn weights(basis: Basis2, grid: &Grid2, p: P2) -> Vec<(usize, f64)> {
    let u = [
        (p[0] - grid.origin) / grid.spacing,
        (p[1] - grid.origin) / grid.spacing,
    ];
    let s = basis.reach();
    let range = |v: f64| ((v - s).floor() as i64 + 1)..=((v + s).ceil() as i64 - 1);
    let mut out = Vec::new();
    match basis {
        Basis2::Pg { n, r } => {
            for j in range(u[1]) {
                for i in range(u[0]) {
                    if i < 0 || j < 0 || i >= grid.n as i64 || j >= grid.n as i64 {
                        continue;
                    }
                    let d2 = (u[0] - i as f64).powi(2) + (u[1] - j as f64).powi(2);
                    if d2 < r * r {
                        let w = (1.0 - d2 / (r * r)).powi(n as i32 + 1);
                        out.push((i as usize + grid.n * j as usize, w));
                    }
                }
            }
        }
        _ => {
            for j in range(u[1]) {
                let wy = basis.profile(u[1] - j as f64);
                if wy == 0.0 {
                    continue;
                }
                for i in range(u[0]) {
                    let w = wy * basis.profile(u[0] - i as f64);
                    if w != 0.0 {
                        out.push((mirror(i, grid.n) + grid.n * mirror(j, grid.n), w));
                    }
                }
            }
        }
    }
    out
}

/// A 2D coefficient field: `f(p) = Σ c_j B_j(p)`.
pub struct Field2 {
    pub basis: Basis2,
    pub grid: Grid2,
    pub coeffs: Vec<f64>,
}

impl Field2 {
    pub fn value(&self, p: P2) -> f64 {
        weights(self.basis, &self.grid, p)
            .into_iter()
            .map(|(j, w)| w * self.coeffs[j])
            .sum()
    }
}
