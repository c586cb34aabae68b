//! What `compare` and `perturb` report, as Python classes with one read-only attribute per
//! figure (the names and meanings of the library's report structs).

use pyo3::prelude::*;

/// `Name(a=…, b=…)` from a report's fields, each as Python would print it.
macro_rules! report_repr {
    ($name:literal, $self:ident, $($field:ident),+) => {{
        let fields: Vec<String> =
            vec![$(format!("{}={}", stringify!($field), $self.$field.py_repr())),+];
        format!("{}({})", $name, fields.join(", "))
    }};
}

/// A report field as Python's `repr` shows the value it converts to.
trait PyRepr {
    fn py_repr(&self) -> String;
}

impl PyRepr for usize {
    fn py_repr(&self) -> String {
        self.to_string()
    }
}

impl PyRepr for f64 {
    fn py_repr(&self) -> String {
        format!("{self:?}")
    }
}

impl PyRepr for bool {
    fn py_repr(&self) -> String {
        if *self { "True" } else { "False" }.to_string()
    }
}

impl PyRepr for String {
    fn py_repr(&self) -> String {
        format!("'{self}'")
    }
}

impl PyRepr for (f64, f64, f64) {
    fn py_repr(&self) -> String {
        format!("({:?}, {:?}, {:?})", self.0, self.1, self.2)
    }
}

/// Topology and size of a mesh.
#[pyclass(frozen, get_all, eq, module = "pgvol")]
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct MeshStats {
    /// Vertices referenced by at least one triangle.
    vertices: usize,
    triangles: usize,
    /// Unique undirected edges.
    edges: usize,
    /// Edges used by exactly one triangle.
    boundary_edges: usize,
    /// Edges used by three or more triangles.
    non_manifold_edges: usize,
    /// Every edge used by exactly two triangles.
    watertight: bool,
    /// Every edge shared by two triangles is traversed once in each direction.
    winding_consistent: bool,
    /// V - E + F.
    euler_characteristic: i64,
    /// Signed volume by the divergence theorem; positive for outward-facing closed meshes.
    volume: f64,
    area: f64,
    /// Connected components, where triangles sharing a vertex are connected.
    components: usize,
}

impl From<pgvol::core::MeshStats> for MeshStats {
    fn from(s: pgvol::core::MeshStats) -> Self {
        MeshStats {
            vertices: s.vertices,
            triangles: s.triangles,
            edges: s.edges,
            boundary_edges: s.boundary_edges,
            non_manifold_edges: s.non_manifold_edges,
            watertight: s.watertight,
            winding_consistent: s.winding_consistent,
            euler_characteristic: s.euler_characteristic,
            volume: s.volume,
            area: s.area,
            components: s.components,
        }
    }
}

#[pymethods]
impl MeshStats {
    fn __repr__(&self) -> String {
        report_repr!(
            "MeshStats",
            self,
            vertices,
            triangles,
            boundary_edges,
            non_manifold_edges,
            watertight,
            components
        )
    }
}

/// Distances from the vertices of mesh A to mesh B, and the angles between their normals.
#[pyclass(frozen, get_all, eq, module = "pgvol")]
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct VertexDeviation {
    vertices: usize,
    mean: f64,
    max: f64,
    /// Angle between A's vertex normal and B's normal at the closest point, in degrees.
    normal_mean_deg: f64,
    normal_max_deg: f64,
}

#[pymethods]
impl VertexDeviation {
    fn __repr__(&self) -> String {
        report_repr!(
            "VertexDeviation",
            self,
            vertices,
            mean,
            max,
            normal_mean_deg
        )
    }
}

/// The depth-buffer difference of one view.
#[pyclass(frozen, get_all, eq, module = "pgvol")]
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct ViewDifference {
    /// The view's depth direction.
    direction: (f64, f64, f64),
    /// Pixels covered by either mesh.
    covered: usize,
    /// Mean absolute depth difference over those pixels, in mesh units.
    mean_abs: f64,
}

#[pymethods]
impl ViewDifference {
    fn __repr__(&self) -> String {
        report_repr!("ViewDifference", self, direction, covered, mean_abs)
    }
}

/// Depth buffers of two meshes rendered from the same views, compared.
#[pyclass(frozen, get_all, eq, module = "pgvol")]
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct DepthDifference {
    views: Vec<ViewDifference>,
    /// Pixels per side of each view.
    resolution: usize,
    /// Mean absolute difference over every covered pixel of every view, in mesh units.
    mean_abs: f64,
}

#[pymethods]
impl DepthDifference {
    fn __repr__(&self) -> String {
        report_repr!("DepthDifference", self, resolution, mean_abs)
    }
}

/// Mesh `a` measured against reference mesh `b`; `_pct` figures are percent of b's
/// bounding-box diagonal.
#[pyclass(frozen, get_all, eq, module = "pgvol")]
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Comparison {
    a: MeshStats,
    b: MeshStats,
    /// Samples drawn on each mesh.
    samples: usize,
    /// Bounding-box diagonal of b.
    diagonal: f64,
    hausdorff: f64,
    hausdorff_pct: f64,
    chamfer_l1: f64,
    chamfer_l1_pct: f64,
    mean_a_to_b: f64,
    mean_b_to_a: f64,
    /// Angle between the normals at each sample and at its closest point on the other mesh,
    /// pooled over both directions, in degrees.
    normal_deviation_mean_deg: f64,
    normal_deviation_p95_deg: f64,
    vertex_deviation: VertexDeviation,
    vertex_deviation_mean_pct: f64,
    vertex_deviation_max_pct: f64,
    /// Depth buffers from 14 views.
    depth_buffer: DepthDifference,
    depth_buffer_pct: f64,
}

impl From<pgvol::Comparison> for Comparison {
    fn from(c: pgvol::Comparison) -> Self {
        let v = c.vertex_deviation;
        let d = c.depth_buffer;
        Comparison {
            a: c.a.into(),
            b: c.b.into(),
            samples: c.samples,
            diagonal: c.diagonal,
            hausdorff: c.hausdorff,
            hausdorff_pct: c.hausdorff_pct,
            chamfer_l1: c.chamfer_l1,
            chamfer_l1_pct: c.chamfer_l1_pct,
            mean_a_to_b: c.mean_a_to_b,
            mean_b_to_a: c.mean_b_to_a,
            normal_deviation_mean_deg: c.normal_deviation_mean_deg,
            normal_deviation_p95_deg: c.normal_deviation_p95_deg,
            vertex_deviation: VertexDeviation {
                vertices: v.vertices,
                mean: v.mean,
                max: v.max,
                normal_mean_deg: v.normal_mean_deg,
                normal_max_deg: v.normal_max_deg,
            },
            vertex_deviation_mean_pct: c.vertex_deviation_mean_pct,
            vertex_deviation_max_pct: c.vertex_deviation_max_pct,
            depth_buffer: DepthDifference {
                views: d
                    .views
                    .iter()
                    .map(|w| ViewDifference {
                        direction: w.direction.into(),
                        covered: w.covered,
                        mean_abs: w.mean_abs,
                    })
                    .collect(),
                resolution: d.resolution,
                mean_abs: d.mean_abs,
            },
            depth_buffer_pct: c.depth_buffer_pct,
        }
    }
}

#[pymethods]
impl Comparison {
    fn __repr__(&self) -> String {
        report_repr!(
            "Comparison",
            self,
            hausdorff,
            hausdorff_pct,
            chamfer_l1,
            normal_deviation_mean_deg,
            samples
        )
    }
}

/// Seeds of the perturbation loop refused, by reason.
#[pyclass(frozen, get_all, eq, module = "pgvol")]
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Refusals {
    /// Fewer than ten vertices of the seed's sign within the trial radius.
    too_few_points: usize,
    /// No solve gave a local bump.
    not_local: usize,
    /// The best bump did not lower the functional.
    no_gain: usize,
    /// The bump put more probes on the wrong side.
    probes: usize,
}

#[pymethods]
impl Refusals {
    fn __repr__(&self) -> String {
        report_repr!("Refusals", self, too_few_points, not_local, no_gain, probes)
    }
}

/// What the perturbation loop did; deviations in mesh units.
#[pyclass(frozen, get_all, eq, module = "pgvol")]
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct PerturbLoop {
    /// Perturbations in the field: the loop's plus the clearing bumps.
    functions: usize,
    /// Perturbations the loop added.
    loop_functions: usize,
    /// Sign points given.
    sign_points: usize,
    /// Sign points on the wrong side of the base quadric.
    wrong_side_of_base: usize,
    /// Sign points on the wrong side after the loop, before its clearing pass.
    wrong_side_before_clearing: usize,
    /// Sign points on the wrong side at the end.
    wrong_side_after: usize,
    vertices: usize,
    /// The mesh's bounding-box diagonal.
    diagonal: f64,
    /// Mean vertex deviation estimate of the base quadric alone.
    base_mean: f64,
    /// Largest vertex deviation estimate of the base quadric alone.
    base_max: f64,
    /// Mean vertex deviation estimate after the last perturbation.
    mean: f64,
    /// Largest vertex deviation estimate after the last perturbation.
    max: f64,
    /// The functional the loop lowers (mean |M| over the vertices) for the base quadric.
    base_functional: f64,
    /// The functional after each accepted perturbation (never increasing).
    history: Vec<f64>,
    /// Whether the base quadric took the exact least-squares fit.
    base_exact: bool,
    /// Trial perturbations evaluated.
    trials: usize,
    seeds_set_aside: usize,
    /// Perturbations whose ten-point system was solved exactly.
    exact_solves: usize,
    /// Descent steps taken on the chosen perturbations' coefficients.
    descent_steps: usize,
    refusals: Refusals,
    /// Why the loop ended: "tolerance", "max_functions", "no_improvement" or "cancelled".
    stop: String,
    seconds: f64,
}

impl From<pgvol::perturbation::PerturbReport> for PerturbLoop {
    fn from(r: pgvol::perturbation::PerturbReport) -> Self {
        use pgvol::perturbation::StopReason;
        let stop = match r.stop {
            StopReason::Tolerance => "tolerance",
            StopReason::MaxFunctions => "max_functions",
            StopReason::NoImprovement => "no_improvement",
            StopReason::Cancelled => "cancelled",
        };
        PerturbLoop {
            functions: r.functions,
            loop_functions: r.loop_functions,
            sign_points: r.sign_points,
            wrong_side_of_base: r.wrong_side_of_base,
            wrong_side_before_clearing: r.wrong_side_before_clearing,
            wrong_side_after: r.wrong_side_after,
            vertices: r.vertices,
            diagonal: r.diagonal,
            base_mean: r.base_mean,
            base_max: r.base_max,
            mean: r.mean,
            max: r.max,
            base_functional: r.base_functional,
            history: r.history,
            base_exact: r.base_exact,
            trials: r.trials,
            seeds_set_aside: r.seeds_set_aside,
            exact_solves: r.exact_solves,
            descent_steps: r.descent_steps,
            refusals: Refusals {
                too_few_points: r.refusals.too_few_points,
                not_local: r.refusals.not_local,
                no_gain: r.refusals.no_gain,
                probes: r.refusals.probes,
            },
            stop: stop.to_string(),
            seconds: r.seconds,
        }
    }
}

impl PyRepr for PerturbLoop {
    fn py_repr(&self) -> String {
        self.__repr__()
    }
}

#[pymethods]
impl PerturbLoop {
    fn __repr__(&self) -> String {
        report_repr!("PerturbLoop", self, functions, mean, max, stop)
    }
}

/// The pass clearing wrong nodes of the check grid away from the surface.
#[pyclass(frozen, get_all, eq, module = "pgvol")]
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Cleanup {
    /// Checked points on the wrong side of the field before the pass.
    wrong_before: usize,
    /// Clearing bumps added.
    bumps: usize,
    /// Checked points still on the wrong side after it.
    wrong_after: usize,
}

impl PyRepr for Cleanup {
    fn py_repr(&self) -> String {
        self.__repr__()
    }
}

#[pymethods]
impl Cleanup {
    fn __repr__(&self) -> String {
        report_repr!("Cleanup", self, wrong_before, bumps, wrong_after)
    }
}

/// The passes removing stray pieces left on the check grid.
#[pyclass(frozen, get_all, eq, module = "pgvol")]
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Strays {
    /// Stray pieces found before the passes.
    pieces: usize,
    /// Their nodes, each given a bump.
    nodes: usize,
    /// Of those, nodes on the mesh's side held by a stray piece (parts thinner than the grid).
    against_mesh: usize,
    /// Passes that found stray pieces.
    rounds: usize,
    /// Stray pieces left after the last pass.
    pieces_left: usize,
}

impl PyRepr for Strays {
    fn py_repr(&self) -> String {
        self.__repr__()
    }
}

#[pymethods]
impl Strays {
    fn __repr__(&self) -> String {
        report_repr!("Strays", self, pieces, nodes, rounds, pieces_left)
    }
}

/// What a conversion by the perturbation method did: the loop, then the two checks.
#[pyclass(frozen, get_all, eq, module = "pgvol")]
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct PerturbReport {
    perturbation: PerturbLoop,
    cleanup: Cleanup,
    strays: Strays,
}

impl PerturbReport {
    pub(crate) fn new(
        report: pgvol::perturbation::PerturbReport,
        cleanup: pgvol::perturbation::Cleanup,
        strays: pgvol::perturbation::Strays,
    ) -> Self {
        PerturbReport {
            perturbation: report.into(),
            cleanup: Cleanup {
                wrong_before: cleanup.wrong_before,
                bumps: cleanup.bumps,
                wrong_after: cleanup.wrong_after,
            },
            strays: Strays {
                pieces: strays.pieces,
                nodes: strays.nodes,
                against_mesh: strays.against_mesh,
                rounds: strays.rounds,
                pieces_left: strays.pieces_left,
            },
        }
    }
}

#[pymethods]
impl PerturbReport {
    fn __repr__(&self) -> String {
        report_repr!("PerturbReport", self, perturbation, cleanup, strays)
    }
}
