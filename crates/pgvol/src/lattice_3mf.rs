//! Lattices and infills as 3MF implicit functions: the part's field travels as the level-set
//! image stack, and the lattice, its grading, the cut to the part and the drains as a node graph
//! that reads it, so a file holds the formula instead of the lattice's surface.
//!
//! The graph computes what `pgvol_ops::Lattice::value` and the lattice operations compute at a
//! node, with the part's value taken from the image stack (exact at the nodes, trilinear in
//! between).

use std::f64::consts::TAU;
use std::path::Path;

use pgvol_core::Grid;
use pgvol_format::implicit::{Binary, ImplicitFunction, Port, Unary};
use pgvol_format::threemf::{image_value, write_3mf_implicit, ImplicitLevelSet};
use pgvol_ops::{Drain, Lattice, LatticeStyle, Ramp, Tpms};

use crate::error::{Error, FileResult, Result};
use crate::field_value::Field;

/// How a lattice meets the part, as in [`Field::lattice`] and [`Field::infill`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LatticeCut {
    /// The part intersected with the lattice: `max(f, lattice)`.
    Part,
    /// The part hollowed to walls of `wall` with the lattice in the cavity:
    /// `max(f, min(−(f + wall), lattice))`.
    Infill {
        /// The wall's thickness, model units.
        wall: f32,
    },
}

/// The image stack's value step, in grid spacings: the error is at most half of it, and a
/// coarser step than the 16 bits allow leaves smooth sheets that compress.
pub const IMAGE_STEP: f32 = 1.0 / 64.0;

/// Shorthands over the graph for the lattice's formulas.
struct Graph {
    f: ImplicitFunction,
}

impl Graph {
    fn c(&mut self, v: f32) -> Port {
        self.f.constant(v as f64)
    }
    fn v(&mut self, v: glam::Vec3) -> Port {
        self.f.constvec(v.as_dvec3().to_array())
    }
    fn add(&mut self, a: &Port, b: &Port) -> Port {
        self.f.binary(Binary::Add, a, b)
    }
    fn sub(&mut self, a: &Port, b: &Port) -> Port {
        self.f.binary(Binary::Sub, a, b)
    }
    fn mul(&mut self, a: &Port, b: &Port) -> Port {
        self.f.binary(Binary::Mul, a, b)
    }
    fn max(&mut self, a: &Port, b: &Port) -> Port {
        self.f.binary(Binary::Max, a, b)
    }
    fn min(&mut self, a: &Port, b: &Port) -> Port {
        self.f.binary(Binary::Min, a, b)
    }
    /// `a + (b − a) s` for constants `a`, `b`.
    fn lerp(&mut self, a: f32, b: f32, s: &Port) -> Port {
        let (a, slope) = (self.c(a), self.c(b - a));
        let scaled = self.mul(&slope, s);
        self.add(&a, &scaled)
    }

    /// The periodic function at phase `u` and its gradient in the phase.
    fn tpms(&mut self, surface: Tpms, u: &Port) -> (Port, Port) {
        let [ux, uy, uz] = self.f.decompose(u);
        let [sx, sy, sz] = [&ux, &uy, &uz].map(|a| self.f.unary(Unary::Sin, a));
        let [cx, cy, cz] = [&ux, &uy, &uz].map(|a| self.f.unary(Unary::Cos, a));
        match surface {
            Tpms::Gyroid => {
                // sin x cos y + sin y cos z + sin z cos x
                let value = self.sum_of_products(&[(&sx, &cy), (&sy, &cz), (&sz, &cx)], &[]);
                let gx = self.sum_of_products(&[(&cx, &cy)], &[(&sz, &sx)]);
                let gy = self.sum_of_products(&[(&cy, &cz)], &[(&sx, &sy)]);
                let gz = self.sum_of_products(&[(&cz, &cx)], &[(&sy, &sz)]);
                let gradient = self.f.compose([&gx, &gy, &gz]);
                (value, gradient)
            }
            Tpms::SchwarzP => {
                let cxy = self.add(&cx, &cy);
                let value = self.add(&cxy, &cz);
                let s = self.f.compose([&sx, &sy, &sz]);
                let zero = self.v(glam::Vec3::ZERO);
                (value, self.sub(&zero, &s))
            }
            Tpms::Diamond => {
                let value = self.sum_of_triples(&[
                    (true, [&sx, &sy, &sz]),
                    (true, [&sx, &cy, &cz]),
                    (true, [&cx, &sy, &cz]),
                    (true, [&cx, &cy, &sz]),
                ]);
                let gx = self.sum_of_triples(&[
                    (true, [&cx, &sy, &sz]),
                    (true, [&cx, &cy, &cz]),
                    (false, [&sx, &sy, &cz]),
                    (false, [&sx, &cy, &sz]),
                ]);
                let gy = self.sum_of_triples(&[
                    (true, [&sx, &cy, &sz]),
                    (false, [&sx, &sy, &cz]),
                    (true, [&cx, &cy, &cz]),
                    (false, [&cx, &sy, &sz]),
                ]);
                let gz = self.sum_of_triples(&[
                    (true, [&sx, &sy, &cz]),
                    (false, [&sx, &cy, &sz]),
                    (false, [&cx, &sy, &sz]),
                    (true, [&cx, &cy, &cz]),
                ]);
                let gradient = self.f.compose([&gx, &gy, &gz]);
                (value, gradient)
            }
            Tpms::Neovius => {
                // 3 (cos x + cos y + cos z) + 4 cos x cos y cos z
                let three = self.c(3.0);
                let four = self.c(4.0);
                let cxy = self.add(&cx, &cy);
                let csum = self.add(&cxy, &cz);
                let a = self.mul(&three, &csum);
                let cxcy = self.mul(&cx, &cy);
                let cxyz = self.mul(&cxcy, &cz);
                let b = self.mul(&four, &cxyz);
                let value = self.add(&a, &b);
                // ∂x = −3 sin x − 4 sin x cos y cos z = −sin x (3 + 4 cos y cos z), and likewise.
                let cycz = self.mul(&cy, &cz);
                let cxcz = self.mul(&cx, &cz);
                let pairs = [(&sx, cycz), (&sy, cxcz), (&sz, cxcy)];
                let mut g = Vec::new();
                for (s, pair) in pairs {
                    let four_pair = self.mul(&four, &pair);
                    let k = self.add(&three, &four_pair);
                    g.push(self.mul(s, &k));
                }
                let s = self.f.compose([&g[0], &g[1], &g[2]]);
                let zero = self.v(glam::Vec3::ZERO);
                (value, self.sub(&zero, &s))
            }
        }
    }

    /// `Σ a·b over plus − Σ a·b over minus`.
    fn sum_of_products(&mut self, plus: &[(&Port, &Port)], minus: &[(&Port, &Port)]) -> Port {
        let mut total: Option<Port> = None;
        for (a, b) in plus {
            let p = self.mul(a, b);
            total = Some(match total {
                Some(t) => self.add(&t, &p),
                None => p,
            });
        }
        let mut total = total.expect("at least one positive term");
        for (a, b) in minus {
            let p = self.mul(a, b);
            total = self.sub(&total, &p);
        }
        total
    }

    /// `Σ ±a·b·c`, each term added (`true`) or subtracted; the first term is added.
    fn sum_of_triples(&mut self, terms: &[(bool, [&Port; 3])]) -> Port {
        let mut total: Option<Port> = None;
        for (plus, [a, b, c]) in terms {
            let ab = self.mul(a, b);
            let p = self.mul(&ab, c);
            total = Some(match (total, plus) {
                (None, _) => p,
                (Some(t), true) => self.add(&t, &p),
                (Some(t), false) => self.sub(&t, &p),
            });
        }
        total.expect("at least one term")
    }
}

/// The graph of `lattice` cut to the part as `cut`, with `drains`, the part's value read from
/// the image stack sampled on `grid`.
pub fn lattice_function(
    lattice: &Lattice,
    cut: LatticeCut,
    drains: &[Drain],
    grid: &Grid,
) -> ImplicitFunction {
    let mut g = Graph {
        f: ImplicitFunction::new(),
    };
    let pos = g.f.position();
    let part = image_value(&mut g.f, grid, &pos);
    let zero = g.c(0.0);
    let one = g.c(1.0);

    // Position on the ramp s ∈ [0, 1], whether its gradient is live, the anchor of the phase.
    let (s, live_axis, anchor) = match lattice.grade.map(|gr| gr.ramp) {
        None => (None, None, glam::Vec3::ZERO),
        Some(Ramp::Depth { depth }) => {
            let k = g.c(-1.0 / depth);
            let raw = g.mul(&part, &k);
            (Some(g.f.clamp(&raw, &zero, &one)), None, glam::Vec3::ZERO)
        }
        Some(Ramp::Linear { from, to }) => {
            let axis = (to - from) / (to - from).length_squared();
            let from_v = g.v(from);
            let axis_v = g.v(axis);
            let rel = g.sub(&pos, &from_v);
            let raw = g.f.dot(&rel, &axis_v);
            // 1 inside [0, 1], else 0: where pgvol's ramp has a gradient.
            let below_end = g.f.select(&one, &raw, &zero, &one);
            let inside = g.f.select(&raw, &zero, &zero, &below_end);
            (
                Some(g.f.clamp(&raw, &zero, &one)),
                Some((inside, axis_v)),
                from,
            )
        }
    };
    let cell = match (lattice.grade, &s) {
        (Some(gr), Some(s)) if gr.cell != lattice.cell => g.lerp(lattice.cell, gr.cell, s),
        _ => g.c(lattice.cell),
    };
    let thickness = match (lattice.grade, &s) {
        (Some(gr), Some(s)) if gr.thickness != lattice.thickness => {
            g.lerp(lattice.thickness, gr.thickness, s)
        }
        _ => g.c(lattice.thickness),
    };
    let anchor_v = g.v(anchor);
    let q = g.sub(&pos, &anchor_v);
    let tau = g.f.constant(TAU);
    let k = g.f.binary(Binary::Div, &tau, &cell);
    let k_v = g.f.splat(&k);
    let u = g.mul(&q, &k_v);
    let (value, gradient) = g.tpms(lattice.surface, &u);

    // ∇ₓf = 2π/L (g − ∇L (q·g) / L), ∇L = (L₁ − L₀) · axis where the ramp is live.
    let gradient = match (lattice.grade, live_axis) {
        (Some(gr), Some((inside, axis_v))) if gr.cell != lattice.cell => {
            let qg = g.f.dot(&q, &gradient);
            let slope = g.c(gr.cell - lattice.cell);
            let a = g.mul(&slope, &inside);
            let b = g.mul(&a, &qg);
            let coef = g.f.binary(Binary::Div, &b, &cell);
            let coef_v = g.f.splat(&coef);
            let shift = g.mul(&coef_v, &axis_v);
            g.sub(&gradient, &shift)
        }
        _ => gradient,
    };
    let world = g.mul(&gradient, &k_v);
    let norm = g.f.length(&world);
    let raw = g.f.binary(Binary::Div, &value, &norm);
    let bound = lattice.clamp();
    let (lo, hi) = (g.c(-bound), g.c(bound));
    let d = g.f.clamp(&raw, &lo, &hi);
    let solid = match lattice.style {
        LatticeStyle::Sheet => {
            let a = g.f.unary(Unary::Abs, &d);
            let half = g.c(0.5);
            let half_t = g.mul(&half, &thickness);
            g.sub(&a, &half_t)
        }
        LatticeStyle::Strut => g.sub(&d, &thickness),
    };
    let mut shape = match cut {
        LatticeCut::Part => g.max(&part, &solid),
        LatticeCut::Infill { wall } => {
            let minus_wall = g.c(-wall);
            let cavity = g.sub(&minus_wall, &part);
            let filled = g.min(&cavity, &solid);
            g.max(&part, &filled)
        }
    };
    for drain in drains {
        let distance = drain_distance(&mut g, drain, &pos);
        let removed = g.sub(&zero, &distance);
        shape = g.max(&shape, &removed);
    }
    g.f.set_output("shape", &shape);
    g.f
}

/// Signed distance to a drain's half-infinite cylinder with a flat cap at its point.
fn drain_distance(g: &mut Graph, drain: &Drain, pos: &Port) -> Port {
    let unit = drain.direction.normalize_or_zero();
    let point = g.v(drain.point);
    let unit_v = g.v(unit);
    let d = g.sub(pos, &point);
    let along = g.f.dot(&d, &unit_v);
    let along_v = g.f.splat(&along);
    let axial = g.mul(&unit_v, &along_v);
    let radial_v = g.sub(&d, &axial);
    let radial_len = g.f.length(&radial_v);
    let radius = g.c(0.5 * drain.diameter);
    let radial = g.sub(&radial_len, &radius);
    let zero = g.c(0.0);
    let cap = g.sub(&zero, &along);
    let inner_max = g.max(&radial, &cap);
    let inner = g.min(&inner_max, &zero);
    let outer_r = g.max(&radial, &zero);
    let outer_c = g.max(&cap, &zero);
    let outer_v = g.f.compose([&outer_r, &outer_c, &zero]);
    let outer = g.f.length(&outer_v);
    g.add(&inner, &outer)
}

/// What [`Field::write_lattice_3mf`] wrote.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImplicitPackage {
    /// The image stack's grid: the part's.
    pub grid: Grid,
    /// Nodes of the implicit function.
    pub nodes: usize,
}

/// The range of part values the graph needs exactly: below it the lattice wins every min and
/// max and the ramp has ended, above it the solid is empty (the value only has to stay
/// positive); two grid spacings either side keep the interpolation near the surface exact.
/// The image stack holds the part clamped to it: a constant compresses to almost nothing.
pub fn part_range(lattice: &Lattice, wall: f32, spacing: f32) -> (f32, f32) {
    let thickest = lattice
        .grade
        .map_or(lattice.thickness, |g| {
            g.thickness.abs().max(lattice.thickness.abs())
        })
        .abs();
    let depth = crate::lattice::lattice_reach(lattice, wall);
    (
        -(depth + lattice.clamp() + thickest + 2.0 * spacing),
        2.0 * spacing,
    )
}

impl Field {
    /// Writes `lattice` cut to this part as `cut`, with `drains`, as a 3MF package: the part's
    /// field as the image stack on its stored grid and the lattice as an implicit function of
    /// it. Checked as [`Field::lattice`] and [`Field::infill`] check, except the lattice's
    /// own resolution (the formula holds any sheet).
    pub fn write_lattice_3mf(
        &self,
        path: impl AsRef<Path>,
        lattice: &Lattice,
        cut: LatticeCut,
        drains: &[Drain],
        unit: &str,
    ) -> Result<ImplicitPackage> {
        let path = path.as_ref();
        crate::export::check_unit(unit).map_err(|e| e.at(path))?;
        crate::frame::require_near(self.file.volume.grid.offset, "a lattice")?;
        lattice.check()?;
        let wall = match cut {
            LatticeCut::Part => 0.0,
            LatticeCut::Infill { wall } => {
                crate::field_value::check_thickness(wall)?;
                wall
            }
        };
        for d in drains {
            if !(d.diameter.is_finite() && d.diameter > 0.0)
                || d.direction.normalize_or_zero() == glam::Vec3::ZERO
                || !d.point.is_finite()
            {
                return Err(Error::parameter(
                    "a drain needs a finite point, a non-zero direction and a positive diameter",
                ));
            }
        }
        self.check_reach(crate::lattice::lattice_reach(lattice, wall))?;
        let grid = self.file.volume.grid;
        crate::memory::check_grid("sampling", &grid, crate::memory::BYTES_PER_SDF_NODE)?;
        let (below, above) = part_range(lattice, wall, grid.spacing);
        let values: Vec<f32> = self
            .file
            .volume
            .sample(&grid)
            .into_iter()
            .map(|v| v.clamp(below, above))
            .collect();
        let function = lattice_function(lattice, cut, drains, &grid);
        // Where the graph is undefined (a zero gradient exactly at a labyrinth's centre): no
        // material.
        let fallback = above as f64;
        let level_set = ImplicitLevelSet {
            function: &function,
            fallback,
            value_step: Some(IMAGE_STEP as f64 * grid.spacing as f64),
        };
        write_3mf_implicit(path, &grid, &values, unit, &level_set).writing()?;
        Ok(ImplicitPackage {
            grid,
            nodes: function.node_count(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use pgvol_ops::Grade;

    fn lattices() -> Vec<Lattice> {
        let mut out = Vec::new();
        for surface in [Tpms::Gyroid, Tpms::SchwarzP, Tpms::Diamond, Tpms::Neovius] {
            out.push(Lattice::sheet(surface, 2.0, 0.3));
            out.push(Lattice {
                style: LatticeStyle::Strut,
                ..Lattice::sheet(surface, 2.0, -0.2)
            });
            out.push(Lattice {
                grade: Some(Grade {
                    ramp: Ramp::Depth { depth: 1.5 },
                    cell: 2.0,
                    thickness: 0.6,
                }),
                ..Lattice::sheet(surface, 2.0, 0.3)
            });
        }
        out
    }

    /// What pgvol's lattice operations make of the part's value `v` at `p`.
    fn cut_value(lattice: &Lattice, cut: LatticeCut, p: Vec3, v: f32) -> f32 {
        let g = lattice.value(p, v);
        match cut {
            LatticeCut::Part => v.max(g),
            LatticeCut::Infill { wall } => v.max((-(v + wall)).min(g)),
        }
    }

    #[test]
    fn clamping_the_part_to_its_range_changes_no_value_inside_and_no_sign_outside() {
        let h = 0.05;
        for lattice in lattices() {
            for cut in [LatticeCut::Part, LatticeCut::Infill { wall: 0.4 }] {
                let wall = match cut {
                    LatticeCut::Part => 0.0,
                    LatticeCut::Infill { wall } => wall,
                };
                let (below, above) = part_range(&lattice, wall, h);
                for i in 0..2000 {
                    let p = Vec3::new(i as f32 * 0.0137, i as f32 * 0.0291, i as f32 * 0.0073);
                    // Deep inside: the clamped part gives the same value.
                    let deep = below - 0.01 * (i % 300) as f32;
                    let exact = cut_value(&lattice, cut, p, deep);
                    let clamped = cut_value(&lattice, cut, p, below);
                    assert!(
                        (exact - clamped).abs() < 1e-5,
                        "{lattice:?} {cut:?} at {deep}: {exact} vs {clamped}"
                    );
                    // Far outside: still outside.
                    let far = above + 0.01 * (i % 300) as f32;
                    assert!(cut_value(&lattice, cut, p, far) > 0.0);
                    assert!(cut_value(&lattice, cut, p, above) > 0.0);
                }
            }
        }
    }

    #[test]
    fn every_surface_makes_a_graph_with_the_shape_output() {
        let grid = Grid {
            origin: Vec3::ZERO,
            spacing: 0.1,
            dims: [8, 8, 8],
            offset: Default::default(),
        };
        for lattice in lattices() {
            let drain = Drain {
                point: Vec3::ZERO,
                direction: Vec3::Z,
                diameter: 0.2,
            };
            let f = lattice_function(&lattice, LatticeCut::Infill { wall: 0.3 }, &[drain], &grid);
            assert_eq!(f.output_name(), Some("shape"));
            let xml = f.xml(4, "t", 0);
            assert!(xml.contains("<i:functioncall ") && xml.contains("<i:clamp "));
            assert!(xml.contains("ref=\"inputs.pos\""));
        }
    }
}
