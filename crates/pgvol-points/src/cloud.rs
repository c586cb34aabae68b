//! The input of a reconstruction: points with optional normals.

use glam::Vec3;

/// Points with optional unit normals (outward).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PointCloud {
    pub points: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
}
