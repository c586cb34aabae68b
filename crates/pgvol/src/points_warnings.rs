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

/// Share of the points at each end of an axis left out of the cloud's core box.
const OUTLIER_SHARE: f64 = 0.01;

/// How many times wider than its core box a cloud's box may be before the few points beyond
/// are named: the grid covers the whole box, so they coarsen the surface by this factor.
const OUTLIER_STRETCH: f32 = 10.0;

/// Warns when a few points lie far from the rest (a scanner's stray returns): the grid spans
/// them, so the surface of the rest is resolved many times more coarsely than it would be.
pub(crate) fn warn_about_outliers(points: &[glam::Vec3], progress: &dyn Progress) {
    if let Some(message) = outliers(points) {
        progress.warn(&message);
    }
}

fn outliers(points: &[glam::Vec3]) -> Option<String> {
    // With fewer points a percent of them is not a few strays.
    if points.len() < 200 {
        return None;
    }
    let cut = (OUTLIER_SHARE * points.len() as f64) as usize;
    let mut core = [0.0f32; 3];
    let mut whole = [0.0f32; 3];
    let mut along = Vec::with_capacity(points.len());
    for a in 0..3 {
        along.clear();
        along.extend(points.iter().map(|p| p[a]));
        let lo = *along.select_nth_unstable_by(cut, f32::total_cmp).1;
        let hi = *along
            .select_nth_unstable_by(points.len() - 1 - cut, f32::total_cmp)
            .1;
        let (min, max) = along
            .iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        (core[a], whole[a]) = (hi - lo, max - min);
    }
    let core_side = core.into_iter().fold(0.0f32, f32::max);
    let whole_side = whole.into_iter().fold(0.0f32, f32::max);
    (core_side > 0.0 && whole_side > OUTLIER_STRETCH * core_side).then(|| {
        format!(
            "a few points lie far from the rest: the cloud spans {} but 98 % of its points lie \
             within {} along every axis, and the grid covers the whole span, so the surface is \
             resolved {:.0} times more coarsely than the points would allow; remove the stray \
             points",
            crate::resolution::figure(whole_side),
            crate::resolution::figure(core_side),
            whole_side / core_side
        )
    })
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

    /// Points on a unit sphere say nothing; one stray point a thousand units away is named.
    #[test]
    fn a_stray_point_far_away_is_named() {
        let mut points: Vec<glam::Vec3> = (0..3000)
            .map(|i| {
                let (t, z) = (i as f32 * 2.399_963, 1.0 - 2.0 * (i as f32 + 0.5) / 3000.0);
                let r = (1.0 - z * z).sqrt();
                glam::Vec3::new(r * t.cos(), r * t.sin(), z)
            })
            .collect();
        assert_eq!(outliers(&points), None);
        points.push(glam::Vec3::splat(1000.0));
        let message = outliers(&points).expect("a stray point named");
        assert!(
            message.contains("a few points lie far from the rest"),
            "{message}"
        );
        // Below 200 points, one is more than the few strays the rule is for.
        let mut few = points[..149].to_vec();
        few.push(glam::Vec3::splat(1000.0));
        assert_eq!(outliers(&few), None);
    }

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
