//! Plane geometry of closed loops shared by the slicer and the simplifier.

/// The signed area, positive for counter-clockwise loops, in f64.
pub(crate) fn signed_area(points: &[[f32; 2]]) -> f64 {
    let n = points.len();
    let mut s = 0.0f64;
    for i in 0..n {
        let [x0, y0] = points[i];
        let [x1, y1] = points[(i + 1) % n];
        s += x0 as f64 * y1 as f64 - x1 as f64 * y0 as f64;
    }
    s * 0.5
}

/// The length of the closed loop through `points`, in f64.
pub(crate) fn perimeter(points: &[[f32; 2]]) -> f64 {
    let n = points.len();
    (0..n)
        .map(|i| {
            let [x0, y0] = points[i];
            let [x1, y1] = points[(i + 1) % n];
            (x1 as f64 - x0 as f64).hypot(y1 as f64 - y0 as f64)
        })
        .sum()
}
