//! What a reconstruction from points changed or could not finish, said through the caller's
//! warning channel: the result is still produced, but the caller should know.

use pgvol_points::PointsReport;

use crate::progress::Progress;

/// Warns about re-oriented or flipped normals and an unconverged solve in `report`, for a grid
/// of spacing `grid_spacing`.
pub(crate) fn warn_about(report: &PointsReport, grid_spacing: f32, progress: &dyn Progress) {
    for message in warnings(report, grid_spacing) {
        progress.warn(&message);
    }
}

fn warnings(report: &PointsReport, grid_spacing: f32) -> Vec<String> {
    let mut out = Vec::new();
    let o = &report.orientation;
    if o.reoriented {
        out.push(format!(
            "{} of {} pairs of neighbouring normals ({:.0} %) pointed to opposite sides of the \
             surface; the normals were re-oriented along a minimum spanning tree of the \
             neighbours (directions kept, signs made consistent, outward at the top): give \
             consistently oriented normals, or none, to avoid this",
            o.disagreeing,
            o.pairs,
            100.0 * o.disagreeing_share()
        ));
    }
    if o.flipped {
        out.push(
            "the given normals point into the solid; they were all flipped to point outward"
                .to_string(),
        );
    }
    if !report.converged {
        out.push(format!(
            "the {} fit stopped at its iteration cap ({} iterations, relative residual {:.1e}) \
             without converging, so the surface between the points may be wrong; the points \
             are {:.1} grid spacings apart on average: a coarser grid (about one point per grid \
             spacing, a spacing near {:.4}) or a denser cloud converges",
            report.method,
            report.iterations,
            report.residual,
            report.spacing / grid_spacing,
            report.spacing
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_clean_report_warns_of_nothing_and_each_problem_is_named() {
        let clean = PointsReport {
            method: "spline",
            spacing: 0.03,
            converged: true,
            ..Default::default()
        };
        assert!(warnings(&clean, 0.01).is_empty());
        let mut bad = clean.clone();
        bad.converged = false;
        bad.iterations = 400;
        bad.orientation.reoriented = true;
        bad.orientation.flipped = true;
        let w = warnings(&bad, 0.01);
        assert_eq!(w.len(), 3, "{w:?}");
        assert!(w[0].contains("re-oriented"), "{}", w[0]);
        assert!(w[1].contains("flipped"), "{}", w[1]);
        assert!(
            w[2].contains("400 iterations") && w[2].contains("3.0 grid spacings"),
            "{}",
            w[2]
        );
        assert!(w.iter().all(|m| !m.contains("--")), "{w:?}");
    }
}
