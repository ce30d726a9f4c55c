//! The check that a numeric factor fits before it is started: one that
//! cannot would be killed midway by the kernel, with no message.

use crate::linalg::error::LinalgError;
use crate::linalg::ordering::Ordering;

/// Refuse a numeric factor of `bytes` (values and scratch; `nnz` entries of
/// L) that exceeds the memory and swap the kernel reports available
/// (`/proc/meminfo`: MemAvailable + SwapFree; no check where that file is
/// missing). This decides only whether to start, never the bits of an
/// answer: a factor that cannot fit would be killed midway, and a refusal
/// ends the solve ([`LinalgError::FactorTooLarge`]). `limit`: the workspace's own.
pub(super) fn fits_in_memory(
    bytes: usize,
    nnz: usize,
    ordering: Ordering,
    limit: Option<u64>,
) -> Result<(), LinalgError> {
    let machine = available_memory();
    // (bytes available, whether the user's limit is the tighter bound)
    let (avail, by_limit) = match (machine, limit) {
        (Some(a), Some(l)) if l < a => (l, true),
        (Some(a), _) => (a, false),
        (None, Some(l)) => (l, true),
        (None, None) => return Ok(()),
    };
    if (bytes as u64) <= avail {
        return Ok(());
    }
    Err(LinalgError::FactorTooLarge {
        bytes: bytes as u64,
        available: avail,
        nnz,
        ordering,
        by_limit,
    })
}

/// MemAvailable + SwapFree of `/proc/meminfo`, in bytes.
fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let field = |name: &str| -> Option<u64> {
        let line = text.lines().find(|l| l.starts_with(name))?;
        let kb: u64 = line[name.len()..]
            .trim()
            .trim_end_matches("kB")
            .trim()
            .parse()
            .ok()?;
        Some(kb * 1024)
    };
    Some(field("MemAvailable:")? + field("SwapFree:").unwrap_or(0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_factor_larger_than_the_memory_is_refused_before_it_starts() {
        let avail = available_memory().expect("/proc/meminfo on Linux");
        assert!(avail > 0);
        assert!(fits_in_memory(1 << 20, 1 << 17, Ordering::Amd, None).is_ok());
        assert!(fits_in_memory(1 << 20, 1 << 17, Ordering::Amd, Some(1 << 20)).is_ok());
        let e = fits_in_memory(1 << 20, 1 << 17, Ordering::Amd, Some(1 << 19)).unwrap_err();
        assert!(e.is_memory());
        assert_eq!(
            e,
            LinalgError::FactorTooLarge {
                bytes: 1 << 20,
                available: 1 << 19,
                nnz: 1 << 17,
                ordering: Ordering::Amd,
                by_limit: true
            }
        );
        assert_eq!(
            e.to_string(),
            "the Cholesky factor (amd ordering, nnz(L) = 131072) needs 1.0 MiB, more than the limit set for the factors (512.0 KiB)"
        );
        let huge = (avail as usize).saturating_mul(2);
        let e = fits_in_memory(huge, huge / 8, Ordering::NestedDissection, None).unwrap_err();
        assert!(
            matches!(
                e,
                LinalgError::FactorTooLarge {
                    ordering: Ordering::NestedDissection,
                    by_limit: false,
                    ..
                }
            ),
            "{e:?}"
        );
        let e = e.to_string();
        assert!(
            e.contains("nested-dissection ordering") && e.contains("the memory and swap available"),
            "{e}"
        );
        // linalg names no settings: the advice is the caller's.
        assert!(!e.contains("[solver]") && !e.contains("try "), "{e}");
    }
}
