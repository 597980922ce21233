//! The memory limit of a run: nodes that size buffers from their parameters (render images,
//! grids, particle sets, decoded images) check the size against it before allocating, so a
//! huge parameter fails with an error that states the size instead of meeting the OOM killer
//! (issue 23). The limit is per allocation request of one node; `--max-memory SIZE` or the
//! environment variable `CGNODES_MAX_MEMORY` set it, by default half the physical memory.

use super::{ExecContext, NodeError};
use std::sync::OnceLock;

/// The environment variable that sets the default limit (a size such as `4G` or `512MiB`).
pub const MAX_MEMORY_ENV: &str = "CGNODES_MAX_MEMORY";

/// The limit when neither option nor environment sets one and /proc/meminfo is unreadable.
pub const FALLBACK_MEMORY_LIMIT: u64 = 8 << 30;

/// Parses a size: a number of bytes with an optional unit, `K`, `M`, `G`, `T` (also `KB` ...,
/// powers of 1000, as `format_size` prints) or `KiB`, `MiB`, `GiB`, `TiB` (powers of 1024),
/// case-insensitive; `1.5G` and `800` are sizes.
pub fn parse_size(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (num, unit) = (&t[..split], t[split..].trim());
    let bad = || format!("'{s}' is not a size (examples: 800M, 4G, 1.5GiB, 100000)");
    let x: f64 = num.parse().map_err(|_| bad())?;
    let mult: f64 = match unit.to_ascii_lowercase().as_str() {
        "" | "b" => 1.0,
        "k" | "kb" => 1e3,
        "m" | "mb" => 1e6,
        "g" | "gb" => 1e9,
        "t" | "tb" => 1e12,
        "kib" => 1024.0,
        "mib" => 1024.0 * 1024.0,
        "gib" => 1024.0 * 1024.0 * 1024.0,
        "tib" => 1024.0 * 1024.0 * 1024.0 * 1024.0,
        _ => return Err(bad()),
    };
    let b = x * mult;
    if !(b.is_finite() && b >= 1.0 && b < u64::MAX as f64) {
        return Err(format!("'{s}' is not a size of at least one byte"));
    }
    Ok(b as u64)
}

/// A size for a person, in decimal units with three significant digits (`160 GB`, `9.6 GB`).
pub fn format_size(bytes: u64) -> String {
    if bytes == u64::MAX {
        return "more than 18 EB".into();
    }
    let units = ["bytes", "kB", "MB", "GB", "TB", "PB", "EB"];
    let mut x = bytes as f64;
    let mut u = 0;
    while x >= 999.5 && u + 1 < units.len() {
        x /= 1000.0;
        u += 1;
    }
    if u == 0 {
        return format!("{bytes} bytes");
    }
    let digits = if x >= 99.95 {
        0
    } else if x >= 9.995 {
        1
    } else {
        2
    };
    let s = format!("{x:.digits$}");
    let s = if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    };
    format!("{s} {}", units[u])
}

/// The product of `factors` (element counts and the bytes per element), saturating at
/// `u64::MAX` instead of overflowing: a saturated size is always over the limit.
pub fn bytes_of(factors: &[u64]) -> u64 {
    factors
        .iter()
        .try_fold(1u64, |acc, &f| acc.checked_mul(f))
        .unwrap_or(u64::MAX)
}

/// The machine's physical memory (MemTotal of /proc/meminfo), if readable.
pub fn physical_memory() -> Option<u64> {
    static TOTAL: OnceLock<Option<u64>> = OnceLock::new();
    *TOTAL.get_or_init(|| {
        let text = std::fs::read_to_string("/proc/meminfo").ok()?;
        let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
        let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
        kib.checked_mul(1024)
    })
}

/// The limit a run uses when `RunOptions::max_memory` is unset: `CGNODES_MAX_MEMORY` when it
/// holds a size, else half the physical memory, else 8 GiB. An unreadable
/// `CGNODES_MAX_MEMORY` is reported once on stderr and ignored.
pub fn default_memory_limit() -> u64 {
    if let Ok(v) = std::env::var(MAX_MEMORY_ENV) {
        match parse_size(&v) {
            Ok(b) => return b,
            Err(e) => {
                static WARNED: OnceLock<()> = OnceLock::new();
                WARNED.get_or_init(|| eprintln!("warning: {MAX_MEMORY_ENV}: {e}; ignored"));
            }
        }
    }
    physical_memory().map_or(FALLBACK_MEMORY_LIMIT, |m| m / 2)
}

impl ExecContext<'_> {
    /// The most memory one buffer request of this node may take, in bytes (`--max-memory`).
    pub fn memory_limit(&self) -> u64 {
        self.memory_limit
    }

    /// Checks that `bytes` (see `bytes_of` for a product that cannot overflow) for `what`
    /// (for example "a 100000x100000 image") fit under the run's memory limit before the node
    /// allocates them; else an invalid-input error on `socket`, the input that sets the size,
    /// stating both sizes.
    pub fn reserve_bytes(&self, socket: &str, what: &str, bytes: u64) -> Result<(), NodeError> {
        if bytes <= self.memory_limit {
            return Ok(());
        }
        Err(NodeError::invalid(
            socket,
            format!(
                "{what} needs {}, over the {} limit (--max-memory or {MAX_MEMORY_ENV})",
                format_size(bytes),
                format_size(self.memory_limit)
            ),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_and_print() {
        assert_eq!(parse_size("800").unwrap(), 800);
        assert_eq!(parse_size("4G").unwrap(), 4_000_000_000);
        assert_eq!(parse_size(" 1.5 GiB ").unwrap(), 3 << 29);
        assert_eq!(parse_size("512mb").unwrap(), 512_000_000);
        for bad in ["", "G", "-1G", "4Q", "1e400", "0", "nan"] {
            assert!(parse_size(bad).is_err(), "{bad}");
        }
        assert_eq!(format_size(160_000_000_000), "160 GB");
        assert_eq!(format_size(9_600_000_000), "9.6 GB");
        assert_eq!(format_size(1_234_567), "1.23 MB");
        assert_eq!(format_size(999), "999 bytes");
        assert_eq!(format_size(u64::MAX), "more than 18 EB");
    }

    #[test]
    fn products_saturate_instead_of_overflowing() {
        assert_eq!(bytes_of(&[100_000, 100_000, 16]), 160_000_000_000);
        assert_eq!(bytes_of(&[u64::MAX / 2, 3]), u64::MAX);
        assert_eq!(bytes_of(&[]), 1);
    }

    #[test]
    fn requests_over_the_limit_fail_with_both_sizes() {
        let mut b = super::super::NodeBuilder::new("t");
        b.add_input::<i64>("width");
        let d = b.build(std::sync::Arc::new(|_: &mut ExecContext| Ok(())));
        let files = super::super::FileEnv::default();
        let mut state = None;
        let mut ctx = ExecContext::standalone(&d, Default::default(), &mut state, &files, 0);
        ctx.set_memory_limit(9_600_000_000);
        assert!(ctx.reserve_bytes("width", "x", 9_600_000_000).is_ok());
        let e = ctx
            .reserve_bytes(
                "width",
                "a 100000x100000 image",
                bytes_of(&[100_000, 100_000, 16]),
            )
            .unwrap_err();
        assert_eq!(e.socket.as_deref(), Some("width"));
        assert_eq!(
            e.message,
            "a 100000x100000 image needs 160 GB, over the 9.6 GB limit (--max-memory or CGNODES_MAX_MEMORY)"
        );
    }
}
