//! Bounds on what a 3MF file may make the reader inflate, hold and place.

/// The bounds of one read.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Limits {
    /// Entries in the zip package.
    pub parts: usize,
    /// Uncompressed bytes of one part.
    pub part_bytes: u64,
    /// Uncompressed bytes of all parts read.
    pub package_bytes: u64,
    /// Uncompressed bytes of a part per compressed byte, past the first [`Limits::slack`]
    /// bytes. Model XML deflates 4 to 10 times; a zip bomb of repeated bytes about 1000 times.
    pub inflation: u64,
    /// Uncompressed bytes any part may have whatever its compressed size.
    pub slack: u64,
    /// Vertices and triangles the build places, every use of an object counted.
    pub vertices: u64,
    pub triangles: u64,
    /// Components inside components.
    pub component_depth: usize,
    /// Nesting of XML elements.
    pub xml_depth: usize,
}

impl Limits {
    /// Generous for real parts (a 50-million-triangle build is far beyond what a field of
    /// 1024³ nodes resolves) and small enough for a workstation's memory.
    pub(crate) const DEFAULT: Limits = Limits {
        parts: 100_000,
        part_bytes: 4 << 30,
        package_bytes: 8 << 30,
        inflation: 100,
        slack: 1 << 20,
        vertices: 50_000_000,
        triangles: 50_000_000,
        component_depth: 64,
        xml_depth: 256,
    };
}
