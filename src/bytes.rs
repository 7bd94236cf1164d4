//! Memory sizes as people read and write them: `--max-memory`'s value, `--plan`'s estimates,
//! a solver's budget in its messages.

/// Bytes as KiB, MiB, GiB or TiB with three significant digits.
pub fn human_bytes(b: u64) -> String {
    let units = ["B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"];
    let mut v = b as f64;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < units.len() {
        v /= 1024.0;
        u += 1;
    }
    if u == 0 {
        format!("{b} B")
    } else {
        format!("{v:.3} {}", units[u])
    }
}

/// Parses a memory size: a number with an optional K, M, G or T suffix (powers of 1024).
pub fn parse_bytes(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let (number, shift) = match t.chars().last().map(|c| c.to_ascii_uppercase()) {
        Some('K') => (&t[..t.len() - 1], 10),
        Some('M') => (&t[..t.len() - 1], 20),
        Some('G') => (&t[..t.len() - 1], 30),
        Some('T') => (&t[..t.len() - 1], 40),
        _ => (t, 0),
    };
    let v: f64 = number
        .trim()
        .parse()
        .map_err(|_| format!("expected a size such as 512M or 8G, found {text}"))?;
    if !(v.is_finite() && v > 0.0) {
        return Err(format!("expected a positive size, found {text}"));
    }
    Ok((v * (1u64 << shift) as f64) as u64)
}
