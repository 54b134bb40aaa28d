//! A small, strict command-line parser shared by every xtask subcommand.
//!
//! Options are `--name value` or `--name=value`; flags are `--name`. Every value is checked
//! against its valid range and a bad one is reported with the option's name and that range, so a
//! typo never silently falls back to a default.

use std::collections::BTreeMap;
use std::fmt;
use std::str::FromStr;

/// A user-facing error: the message names the option and what was expected.
#[derive(Debug, Clone, PartialEq)]
pub struct ArgError(pub String);

impl fmt::Display for ArgError {
    fn fmt(&self, formatter: &mut fmt::Formatter<'_>) -> fmt::Result {
        formatter.write_str(&self.0)
    }
}

impl std::error::Error for ArgError {}

/// Parsed `--option value` pairs and `--flag`s of one subcommand.
#[derive(Debug, Default)]
pub struct Args {
    values: BTreeMap<String, String>,
    flags: Vec<String>,
    consumed: Vec<String>,
}

impl Args {
    /// Splits `raw` into options and flags. `flag_names` lists the options that take no value.
    pub fn parse(raw: &[String], flag_names: &[&str]) -> Result<Self, ArgError> {
        let mut args = Args::default();
        let mut index = 0;
        while index < raw.len() {
            let word = &raw[index];
            let Some(body) = word.strip_prefix("--") else {
                return Err(ArgError(format!(
                    "unexpected argument `{word}`: options start with `--`"
                )));
            };
            if let Some((name, value)) = body.split_once('=') {
                args.values.insert(name.to_string(), value.to_string());
            } else if flag_names.contains(&body) {
                args.flags.push(body.to_string());
            } else {
                let Some(value) = raw.get(index + 1) else {
                    return Err(ArgError(format!("option `--{body}` needs a value")));
                };
                args.values.insert(body.to_string(), value.clone());
                index += 1;
            }
            index += 1;
        }
        Ok(args)
    }

    /// True when `--name` was given as a flag.
    pub fn flag(&mut self, name: &str) -> bool {
        self.consumed.push(name.to_string());
        self.flags.iter().any(|flag| flag == name)
    }

    /// The raw text of `--name`, if given.
    pub fn text(&mut self, name: &str) -> Option<String> {
        self.consumed.push(name.to_string());
        self.values.get(name).cloned()
    }

    /// A number in `[min, max]`, or `default` when the option is absent.
    pub fn number<T>(&mut self, name: &str, default: T, min: T, max: T) -> Result<T, ArgError>
    where
        T: FromStr + PartialOrd + Copy + fmt::Display,
    {
        match self.text(name) {
            None => Ok(default),
            Some(text) => {
                let range = format!("a number from {min} to {max}");
                let value: T = text
                    .parse()
                    .map_err(|_| ArgError(format!("option `--{name}`: `{text}` is not {range}")))?;
                // `!(a <= b)` rather than `a > b` so that a NaN is rejected too.
                if !(min <= value && value <= max) {
                    return Err(ArgError(format!(
                        "option `--{name}`: {value} is out of range, expected {range}"
                    )));
                }
                Ok(value)
            }
        }
    }

    /// One of `choices`, or `default` when the option is absent.
    pub fn choice(
        &mut self,
        name: &str,
        default: &'static str,
        choices: &[&'static str],
    ) -> Result<&'static str, ArgError> {
        match self.text(name) {
            None => Ok(default),
            Some(text) => choices
                .iter()
                .copied()
                .find(|choice| *choice == text)
                .ok_or_else(|| {
                    ArgError(format!(
                        "option `--{name}`: `{text}` is not one of {}",
                        choices.join(", ")
                    ))
                }),
        }
    }

    /// Fails on any option or flag that no accessor asked for (a misspelt option is an error).
    pub fn finish(self) -> Result<(), ArgError> {
        let unknown: Vec<&String> = self
            .values
            .keys()
            .chain(self.flags.iter())
            .filter(|name| !self.consumed.contains(name))
            .collect();
        match unknown.first() {
            None => Ok(()),
            Some(name) => Err(ArgError(format!("unknown option `--{name}`"))),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn words(text: &str) -> Vec<String> {
        text.split_whitespace().map(str::to_string).collect()
    }

    #[test]
    fn out_of_range_value_names_option_and_range() {
        let mut args = Args::parse(&words("--seconds 99"), &[]).unwrap();
        let error = args.number("seconds", 1.0, 0.0, 60.0).unwrap_err();
        assert!(error.0.contains("--seconds"), "{error}");
        assert!(error.0.contains("0 to 60"), "{error}");
    }

    #[test]
    fn nan_is_rejected() {
        let mut args = Args::parse(&words("--kb=NaN"), &[]).unwrap();
        assert!(args.number("kb", 1.0, 0.0, 1e12).is_err());
    }

    #[test]
    fn unknown_option_is_an_error() {
        let mut args = Args::parse(&words("--lossless --sekonds 2"), &["lossless"]).unwrap();
        assert!(args.flag("lossless"));
        assert_eq!(args.number("seconds", 1.0, 0.0, 60.0).unwrap(), 1.0);
        assert!(args.finish().unwrap_err().0.contains("--sekonds"));
    }

    #[test]
    fn choice_lists_the_valid_words() {
        let mut args = Args::parse(&words("--thread maybe"), &[]).unwrap();
        let error = args.choice("thread", "on", &["on", "off"]).unwrap_err();
        assert!(error.0.contains("on, off"), "{error}");
    }
}
