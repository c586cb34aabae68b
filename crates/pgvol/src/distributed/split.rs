//! Cutting a range into parts of nearly equal length.

use std::ops::Range;

use crate::error::{Error, Result};

/// `0..n` cut into at most `parts` contiguous ranges whose lengths differ by at most one.
pub fn split(n: usize, parts: usize) -> Result<Vec<Range<usize>>> {
    if parts == 0 {
        return Err(Error::parameter("the number of parts must be at least 1"));
    }
    let parts = parts.min(n.max(1));
    let (base, extra) = (n / parts, n % parts);
    let mut out = Vec::with_capacity(parts);
    let mut start = 0;
    for p in 0..parts {
        let len = base + usize::from(p < extra);
        out.push(start..start + len);
        start += len;
    }
    Ok(out)
}
