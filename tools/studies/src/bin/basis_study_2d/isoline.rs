//! The zero isoline of a fitted field, traced by marching squares on a fine sampling with each
//! vertex refined on the continuous field, and its error against the true shape.

use super::basis2d::Field2;
use super::shapes::{Shape, P2};

/// Field values on a fine square sampling of the grid box.
pub struct Samples {
    pub n: usize,
    pub origin: f64,
    pub step: f64,
    pub values: Vec<f64>,
}

impl Samples {
    pub fn new(field: &Field2, per_spacing: usize) -> Samples {
        let g = field.grid;
        let n = (g.n - 1) * per_spacing + 1;
        let step = g.spacing / per_spacing as f64;
        let values = (0..n * n)
            .map(|i| {
                let (x, y) = (i % n, i / n);
                field.value([g.origin + step * x as f64, g.origin + step * y as f64])
            })
            .collect();
        Samples {
            n,
            origin: g.origin,
            step,
            values,
        }
    }
    pub fn point(&self, x: usize, y: usize) -> P2 {
        [
            self.origin + self.step * x as f64,
            self.origin + self.step * y as f64,
        ]
    }
}

/// Isoline segments; vertex ids name the sampling edge they lie on, so chains can be joined.
pub struct Isoline {
    pub segments: Vec<([P2; 2], [usize; 2])>,
}

/// The zero crossing on the segment a–b (values fa, fb of opposite sign), by regula falsi
/// (Illinois) on the continuous field.
fn root(field: &Field2, a: P2, b: P2, fa: f64, fb: f64) -> P2 {
    let lerp = |t: f64| [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
    let (mut t0, mut t1, mut f0, mut f1) = (0.0, 1.0, fa, fb);
    let mut side = 0;
    for _ in 0..30 {
        let t = (t0 * f1 - t1 * f0) / (f1 - f0);
        let ft = field.value(lerp(t));
        if ft == 0.0 || (t1 - t0).abs() < 1e-12 {
            return lerp(t);
        }
        if (ft < 0.0) == (f0 < 0.0) {
            t0 = t;
            f0 = ft;
            if side == -1 {
                f1 *= 0.5;
            }
            side = -1;
        } else {
            t1 = t;
            f1 = ft;
            if side == 1 {
                f0 *= 0.5;
            }
            side = 1;
        }
    }
    lerp((t0 * f1 - t1 * f0) / (f1 - f0))
}

pub fn trace(field: &Field2, s: &Samples) -> Isoline {
    let n = s.n;
    let v = |x: usize, y: usize| s.values[x + n * y];
    // Edge ids: horizontal edge from (x, y) is 2·(x + n·y), vertical is that + 1.
    let mut segments = Vec::new();
    for y in 0..n - 1 {
        for x in 0..n - 1 {
            let corners = [(x, y), (x + 1, y), (x + 1, y + 1), (x, y + 1)];
            let vals = corners.map(|(a, b)| v(a, b));
            let edges = [
                (0, 1, 2 * (x + n * y)),
                (1, 2, 2 * (x + 1 + n * y) + 1),
                (3, 2, 2 * (x + n * (y + 1))),
                (0, 3, 2 * (x + n * y) + 1),
            ];
            let mut crossings = Vec::new();
            for (a, b, id) in edges {
                if (vals[a] < 0.0) != (vals[b] < 0.0) {
                    let (pa, pb) = (
                        s.point(corners[a].0, corners[a].1),
                        s.point(corners[b].0, corners[b].1),
                    );
                    crossings.push((root(field, pa, pb, vals[a], vals[b]), id));
                }
            }
            match crossings.len() {
                2 => segments.push((
                    [crossings[0].0, crossings[1].0],
                    [crossings[0].1, crossings[1].1],
                )),
                4 => {
                    // Saddle: the centre's sign decides which pairs join.
                    let c = field.value([
                        s.origin + s.step * (x as f64 + 0.5),
                        s.origin + s.step * (y as f64 + 0.5),
                    ]);
                    let pairs = if (c < 0.0) == (vals[0] < 0.0) {
                        [(0, 1), (2, 3)]
                    } else {
                        [(0, 3), (1, 2)]
                    };
                    for (a, b) in pairs {
                        segments.push((
                            [crossings[a].0, crossings[b].0],
                            [crossings[a].1, crossings[b].1],
                        ));
                    }
                }
                _ => {}
            }
        }
    }
    Isoline { segments }
}

fn find(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

impl Isoline {
    /// Connected pieces (closed loops or chains ending on the border).
    pub fn components(&self) -> usize {
        let mut ids: Vec<usize> = self.segments.iter().flat_map(|s| s.1).collect();
        ids.sort_unstable();
        ids.dedup();
        let at = |id: usize| ids.binary_search(&id).unwrap_or(0);
        let mut parent: Vec<usize> = (0..ids.len()).collect();
        for s in &self.segments {
            let (a, b) = (find(&mut parent, at(s.1[0])), find(&mut parent, at(s.1[1])));
            parent[a] = b;
        }
        (0..ids.len())
            .filter(|&i| find(&mut parent, i) == i)
            .count()
    }
}

/// Isoline error against the true shape, in spacings.
#[derive(Clone, Copy, Debug, Default)]
pub struct IsoError {
    /// Length-weighted RMS and max of the true distance from isoline points to the shape.
    pub rms: f64,
    pub max: f64,
    /// Max distance from the true shape to the isoline (large when parts are missing).
    pub reverse_max: f64,
    pub pieces: usize,
}

impl IsoError {
    pub fn hausdorff(&self) -> f64 {
        self.max.max(self.reverse_max)
    }
}

fn segment_distance(p: P2, a: P2, b: P2) -> f64 {
    let ab = [b[0] - a[0], b[1] - a[1]];
    let len2 = ab[0] * ab[0] + ab[1] * ab[1];
    let t = if len2 > 0.0 {
        (((p[0] - a[0]) * ab[0] + (p[1] - a[1]) * ab[1]) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p[0] - a[0] - t * ab[0]).hypot(p[1] - a[1] - t * ab[1])
}

pub fn error(iso: &Isoline, shape: &Shape, spacing: f64) -> IsoError {
    if iso.segments.is_empty() {
        return IsoError {
            rms: f64::INFINITY,
            max: f64::INFINITY,
            reverse_max: f64::INFINITY,
            pieces: 0,
        };
    }
    let (mut sum, mut len, mut max) = (0.0, 0.0, 0.0f64);
    for (p, _) in &iso.segments {
        let (da, db) = (shape.sdf(p[0]).0.abs(), shape.sdf(p[1]).0.abs());
        let l = (p[1][0] - p[0][0]).hypot(p[1][1] - p[0][1]);
        sum += l * (da * da + db * db) / 2.0;
        len += l;
        max = max.max(da).max(db);
    }
    let reverse_max = shape
        .boundary(720)
        .into_iter()
        .map(|q| {
            iso.segments
                .iter()
                .map(|(p, _)| segment_distance(q, p[0], p[1]))
                .fold(f64::INFINITY, f64::min)
        })
        .fold(0.0, f64::max);
    IsoError {
        rms: (sum / len.max(1e-300)).sqrt() / spacing,
        max: max / spacing,
        reverse_max: reverse_max / spacing,
        pieces: iso.components(),
    }
}
