//! Standard output that reports failure instead of panicking: a full disk or a closed pipe
//! (`pgvol info F.pgv > /dev/full`, `pgvol compare A B | head -1`) is an error with exit code 1.

use std::fmt;
use std::io::Write;

/// Writes one line to standard output.
pub fn line(args: fmt::Arguments<'_>) -> anyhow::Result<()> {
    let mut out = std::io::stdout().lock();
    out.write_fmt(args)
        .and_then(|()| out.write_all(b"\n"))
        .and_then(|()| out.flush())
        .map_err(|e| anyhow::anyhow!("cannot write to standard output: {e}"))
}

/// `println!` that returns the write error from the enclosing function.
macro_rules! outln {
    ($($arg:tt)*) => {
        $crate::output::line(format_args!($($arg)*))?
    };
}
pub(crate) use outln;
