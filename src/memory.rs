//! Memory the input asks for, checked before it is allocated.
//!
//! A scene of a few bytes can ask for a 32768² film, a 16384² sphere or a 20000² texture.
//! An allocation that fails aborts the process instead of returning an error, and one
//! that succeeds on an overcommitting system gets the process killed later; so the sizes
//! that come from the input are estimated first and refused with one line that says how
//! much is needed and how much the machine has.

/// Why a size was refused.
#[derive(Debug, thiserror::Error)]
pub enum MemoryError {
    /// The input asks for more memory than the machine has.
    #[error(
        "{what}: needs about {}, and {} is available (the environment variable {LIMIT_VAR} sets the limit)",
        human(*.needed),
        human(*.available)
    )]
    TooLarge {
        /// What needs the memory.
        what: String,
        /// Bytes needed.
        needed: u64,
        /// Bytes available.
        available: u64,
    },
    /// The system refused an allocation the estimate let through.
    #[error("{what}: the system refused the {} it needs", human(*.needed))]
    Refused {
        /// What needs the memory.
        what: String,
        /// Bytes needed.
        needed: u64,
    },
    /// The limit given in [`LIMIT_VAR`] does not parse.
    #[error("{LIMIT_VAR}={0}: expected a size such as 512M or 8G")]
    BadLimit(String),
}

type Result<T> = std::result::Result<T, MemoryError>;

/// Environment variable that sets the memory glint may use (e.g. `512M`, `8G`), in place
/// of the memory the system reports as available.
pub const LIMIT_VAR: &str = "GLINT_MAX_MEMORY";

/// Bytes the render tables and BVH take per triangle once a scene is prepared: world
/// positions, normals, texture coordinates, material index, BVH nodes and indices
/// (MetalRoughSpheres, 1.04M triangles, peaks at 242 MB).
pub const BYTES_PER_PREPARED_TRIANGLE: u64 = 240;

/// Bytes an instance of a shared mesh takes once prepared: its two affine maps, mesh
/// and material indices and its share of the top-level BVH (165 measured at 10^6).
pub const BYTES_PER_INSTANCE: u64 = 200;

/// Bytes a mesh holds per vertex (position, normal, texture coordinates) and per triangle.
pub const BYTES_PER_VERTEX: u64 = 32;
/// See [`BYTES_PER_VERTEX`].
pub const BYTES_PER_TRIANGLE: u64 = 12;

/// The memory glint may use: [`LIMIT_VAR`] if set, else the system's available memory;
/// `None` where neither is known (then nothing is refused in advance).
pub fn budget() -> Result<Option<u64>> {
    if let Ok(text) = std::env::var(LIMIT_VAR) {
        return parse_size(&text)
            .map(Some)
            .ok_or(MemoryError::BadLimit(text));
    }
    Ok(system_available())
}

/// Refuses `parts` (what needs memory, bytes) when their sum exceeds the [`budget`].
pub fn ensure_fits(parts: &[(String, u64)]) -> Result<()> {
    let needed = parts
        .iter()
        .map(|(_, b)| *b)
        .fold(0u64, u64::saturating_add);
    let Some(available) = budget()? else {
        return Ok(());
    };
    if needed <= available {
        return Ok(());
    }
    // Parts under 1% of the total would only lengthen the message.
    let named: Vec<_> = parts
        .iter()
        .filter(|(_, b)| *b > 0 && b.saturating_mul(100) >= needed)
        .collect();
    let what = match named[..] {
        [(what, _)] => what.clone(),
        _ => format!(
            "the render ({})",
            named
                .iter()
                .map(|(what, b)| format!("{what}: {}", human(*b)))
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    Err(MemoryError::TooLarge {
        what,
        needed,
        available,
    })
}

/// `a * b * c` without overflow (sizes from the input can be anything).
pub fn product(factors: &[u64]) -> u64 {
    factors.iter().fold(1u64, |p, f| p.saturating_mul(*f))
}

/// A byte count for people: `25.8 GB`.
pub fn human(bytes: u64) -> String {
    const UNITS: [&str; 5] = ["B", "KB", "MB", "GB", "TB"];
    let mut value = bytes as f64;
    let mut unit = 0;
    while value >= 1000.0 && unit + 1 < UNITS.len() {
        value /= 1000.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{bytes} B")
    } else {
        format!("{value:.1} {}", UNITS[unit])
    }
}

/// Parses `123`, `512K`, `512M`, `8G`, `1T` (powers of 1024; a trailing `B` or `iB` is
/// accepted).
fn parse_size(text: &str) -> Option<u64> {
    let t = text.trim().to_ascii_uppercase();
    let t = t
        .strip_suffix("IB")
        .or_else(|| t.strip_suffix('B'))
        .unwrap_or(&t);
    let (digits, shift) = match t.chars().last()? {
        'K' => (&t[..t.len() - 1], 10),
        'M' => (&t[..t.len() - 1], 20),
        'G' => (&t[..t.len() - 1], 30),
        'T' => (&t[..t.len() - 1], 40),
        _ => (t, 0),
    };
    let value: f64 = digits.trim().parse().ok()?;
    (value.is_finite() && value >= 0.0).then(|| (value * (1u64 << shift) as f64) as u64)
}

/// `MemAvailable` of `/proc/meminfo` (Linux); `None` elsewhere.
fn system_available() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse() {
        assert_eq!(parse_size("123"), Some(123));
        assert_eq!(parse_size("2K"), Some(2048));
        assert_eq!(parse_size("512M"), Some(512 << 20));
        assert_eq!(parse_size("8g"), Some(8 << 30));
        assert_eq!(parse_size("1.5GiB"), Some(3 << 29));
        assert_eq!(parse_size("lots"), None);
        assert_eq!(parse_size("-1G"), None);
    }

    #[test]
    fn bytes_read_for_people() {
        assert_eq!(human(999), "999 B");
        assert_eq!(human(25_769_803_776), "25.8 GB");
    }

    #[test]
    fn products_saturate() {
        assert_eq!(product(&[32768, 32768, 28]), 30_064_771_072);
        assert_eq!(product(&[u64::MAX, 2]), u64::MAX);
    }

    #[test]
    fn the_system_reports_memory_on_linux() {
        if cfg!(target_os = "linux") {
            assert!(system_available().is_some_and(|b| b > 0));
        }
    }
}
