//! Where a call spent its time.

/// Seconds spent per stage of a call.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Timings {
    /// Reading the input.
    pub read: f64,
    /// Signed distances.
    pub sdf: f64,
    /// Fitting the coefficients.
    pub fit: f64,
    /// Finding and storing sharp-feature vertices.
    pub sharp: f64,
    /// Contouring.
    pub contour: f64,
    /// Writing the output.
    pub write: f64,
}
