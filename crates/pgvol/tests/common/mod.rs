//! Helpers shared by the integration tests that bound a process's memory. Each test file
//! compiles this module on its own and uses part of it.
#![allow(dead_code)]

/// Peak resident memory of this process so far, in bytes (`VmHWM`).
pub fn peak_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Fails the test when this process's peak memory so far reached `bound` bytes.
pub fn assert_peak_below(bound: u64) {
    let peak = peak_bytes().expect("VmHWM in /proc/self/status");
    assert!(
        peak < bound,
        "peak memory {} MB over the bound {} MB",
        peak / 1_000_000,
        bound / 1_000_000
    );
}

/// A 32-sided prism of radius 1 and length 200 along z: a small surface on a long grid axis.
pub fn thin_rod() -> pgvol::mesh::Mesh {
    let mut rod = pgvol::mesh::shapes::prism(32);
    for p in &mut rod.positions {
        p.z *= 100.0;
    }
    rod
}
