//! Numbers in user-facing messages, shared by every layer (scene, motion, record, analysis,
//! service, cli): computed values are shown to a sensible number of significant digits, so a
//! step of 0.0050000000000000044 s reads 0.005 s. Values written to data files keep full
//! precision; this is for text meant to be read.

/// Significant digits of [`sig`]: six resolve any input a user typed and any difference a
/// message reports, and hide the last-bit noise of accumulated floating-point sums.
pub const MESSAGE_DIGITS: usize = 6;

/// `x` rounded to [`MESSAGE_DIGITS`] significant digits, printed in Rust's shortest form
/// (`0.005`, `3`, `2.5e-7`, `20000000000`).
pub fn sig(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return x.to_string();
    }
    let rounded: f64 = format!("{:.*e}", MESSAGE_DIGITS - 1, x)
        .parse()
        .unwrap_or(x);
    rounded.to_string()
}

#[cfg(test)]
mod tests {
    use super::sig;

    #[test]
    fn noise_is_rounded_away_and_plain_values_are_kept() {
        assert_eq!(sig(0.0050000000000000044), "0.005");
        assert_eq!(sig(2.9999999999999925), "3");
        assert_eq!(sig(0.1 + 0.2), "0.3");
        assert_eq!(sig(-1.25), "-1.25");
        assert_eq!(sig(123456789.0), "123457000");
        assert_eq!(sig(0.0), "0");
        assert_eq!(sig(f64::INFINITY), "inf");
    }
}
