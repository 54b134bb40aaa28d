//! What the subcommands' command lines share (clap parses them; `main.rs` holds the command
//! tree): value parsers that check a number against its valid range, so that a bad value is
//! reported with the option's name and that range and never silently falls back to a default.

use std::fmt::Display;
use std::str::FromStr;

/// A clap value parser for a number in `[min, max]` (a NaN is rejected).
pub fn number_in<T>(
    min: T,
    max: T,
) -> impl Fn(&str) -> Result<T, String> + Clone + Send + Sync + 'static
where
    T: FromStr + PartialOrd + Copy + Display + Send + Sync + 'static,
{
    move |text: &str| {
        let range = format!("a number from {min} to {max}");
        let value: T = text
            .trim()
            .parse()
            .map_err(|_| format!("`{text}` is not {range}"))?;
        // `!(a <= b)` rather than `a > b` so that a NaN is rejected too.
        if !(min <= value && value <= max) {
            return Err(format!("{value} is out of range, expected {range}"));
        }
        Ok(value)
    }
}

/// A clap value parser for a number that `valid` accepts; `expected` says which.
pub fn number_where(
    valid: fn(f64) -> bool,
    expected: &'static str,
) -> impl Fn(&str) -> Result<f64, String> + Clone + Send + Sync + 'static {
    move |text: &str| match text.trim().parse::<f64>() {
        Ok(value) if valid(value) => Ok(value),
        Ok(value) => Err(format!("{value} is out of range, expected {expected}")),
        Err(_) => Err(format!("`{text}` is not a number ({expected})")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn out_of_range_and_nan_are_rejected_with_the_range() {
        let seconds = number_in(0.0, 60.0);
        assert_eq!(seconds("12.5"), Ok(12.5));
        let error = seconds("99").unwrap_err();
        assert!(error.contains("0 to 60"), "{error}");
        assert!(seconds("NaN").is_err());
        assert!(seconds("soon")
            .unwrap_err()
            .contains("not a number from 0 to 60"));
        let blocks = number_in(1usize, 65_536);
        assert!(blocks("0").is_err() && blocks("-3").is_err());
        let lambda = number_where(|value| value > 0.0 && value <= 1.0, "0 < lambda <= 1");
        assert!(lambda("0").unwrap_err().contains("0 < lambda <= 1"));
    }
}
