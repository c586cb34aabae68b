//! Exact 2D signed distances (negative inside) of the paper's test shapes: circles, squares
//! at several angles and rectangles, with unit gradients and points on their boundaries.

use std::f64::consts::TAU;

pub type P2 = [f64; 2];

#[derive(Clone, Debug)]
pub enum Kind {
    Circle {
        radius: f64,
    },
    /// A rectangle with half-extents `half`, rotated counter-clockwise by `angle` radians.
    Rect {
        half: P2,
        angle: f64,
    },
}

#[derive(Clone, Debug)]
pub struct Shape {
    pub name: String,
    pub centre: P2,
    pub kind: Kind,
}

fn rotate(p: P2, angle: f64) -> P2 {
    let (s, c) = angle.sin_cos();
    [c * p[0] - s * p[1], s * p[0] + c * p[1]]
}

impl Shape {
    /// Signed distance and its unit gradient (away from the closest boundary point).
    pub fn sdf(&self, p: P2) -> (f64, P2) {
        let d = [p[0] - self.centre[0], p[1] - self.centre[1]];
        match self.kind {
            Kind::Circle { radius } => {
                let len = d[0].hypot(d[1]);
                let g = if len > 0.0 {
                    [d[0] / len, d[1] / len]
                } else {
                    [1.0, 0.0]
                };
                (len - radius, g)
            }
            Kind::Rect { half, angle } => {
                let l = rotate(d, -angle);
                let sign = [l[0].signum(), l[1].signum()];
                let q = [l[0].abs() - half[0], l[1].abs() - half[1]];
                let out = [q[0].max(0.0), q[1].max(0.0)];
                let out_len = out[0].hypot(out[1]);
                let (dist, gl) = if out_len > 0.0 {
                    let g = [out[0] / out_len * sign[0], out[1] / out_len * sign[1]];
                    (out_len, g)
                } else if q[0] > q[1] {
                    (q[0], [sign[0], 0.0])
                } else {
                    (q[1], [0.0, sign[1]])
                };
                (dist, rotate(gl, angle))
            }
        }
    }

    /// `n` points spread evenly along the boundary.
    pub fn boundary(&self, n: usize) -> Vec<P2> {
        let at = |p: P2| [p[0] + self.centre[0], p[1] + self.centre[1]];
        match self.kind {
            Kind::Circle { radius } => (0..n)
                .map(|i| {
                    let t = TAU * i as f64 / n as f64;
                    at([radius * t.cos(), radius * t.sin()])
                })
                .collect(),
            Kind::Rect { half, angle } => {
                let perimeter = 4.0 * (half[0] + half[1]);
                (0..n)
                    .map(|i| {
                        let mut s = perimeter * i as f64 / n as f64;
                        let sides = [
                            ([half[0], -half[1]], [0.0, 1.0], 2.0 * half[1]),
                            ([half[0], half[1]], [-1.0, 0.0], 2.0 * half[0]),
                            ([-half[0], half[1]], [0.0, -1.0], 2.0 * half[1]),
                            ([-half[0], -half[1]], [1.0, 0.0], 2.0 * half[0]),
                        ];
                        for (start, dir, len) in sides {
                            if s <= len {
                                let p = [start[0] + dir[0] * s, start[1] + dir[1] * s];
                                return at(rotate(p, angle));
                            }
                            s -= len;
                        }
                        at(rotate([half[0], -half[1]], angle))
                    })
                    .collect()
            }
        }
    }
}

/// The study's shapes on the 13 × 13 grid over [-6, 6]² (spacing 1): every zero set keeps at
/// least one spacing from the border, as the paper advises.
pub fn study_shapes() -> Vec<Shape> {
    let square = |deg: f64| Shape {
        name: format!("square {deg}°"),
        centre: [0.17, -0.11],
        kind: Kind::Rect {
            half: [3.2, 3.2],
            angle: deg.to_radians(),
        },
    };
    let rect = |deg: f64| Shape {
        name: format!("rectangle {deg}°"),
        centre: [0.13, 0.21],
        kind: Kind::Rect {
            half: [4.1, 2.0],
            angle: deg.to_radians(),
        },
    };
    vec![
        Shape {
            name: "circle".into(),
            centre: [0.31, -0.23],
            kind: Kind::Circle { radius: 4.1 },
        },
        square(0.0),
        square(10.0),
        square(22.5),
        square(30.0),
        square(45.0),
        rect(0.0),
        rect(30.0),
        rect(60.0),
    ]
}
