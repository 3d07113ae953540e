//! Build parameters given on the command line as `key=value` pairs (e.g. `lambda=5`,
//! `bvh.preset=fast`), parsed by each builder with its own defaults.

use std::collections::BTreeMap;
use std::str::FromStr;

use crate::BuildError;

#[derive(Clone, Debug, Default, PartialEq)]
pub struct Params {
    values: BTreeMap<String, String>,
}

impl Params {
    /// Parses `key=value` items; an item without `=` is an error naming it.
    pub fn parse<'a>(items: impl IntoIterator<Item = &'a str>) -> Result<Self, BuildError> {
        let mut values = BTreeMap::new();
        for item in items {
            let (k, v) = item
                .split_once('=')
                .ok_or_else(|| BuildError::BadParam { key: item.to_string(), detail: "expected key=value".into() })?;
            values.insert(k.trim().to_string(), v.trim().to_string());
        }
        Ok(Self { values })
    }

    /// The value of `key` parsed as `T`, or `default` when absent.
    pub fn get<T: FromStr>(&self, key: &str, default: T) -> Result<T, BuildError>
    where
        T::Err: std::fmt::Display,
    {
        match self.values.get(key) {
            None => Ok(default),
            Some(raw) => raw.parse().map_err(|e: T::Err| BuildError::BadParam {
                key: key.into(),
                detail: format!("cannot parse '{raw}': {e}"),
            }),
        }
    }

    /// The value of `key` as one of the named `options` (`default` when absent); anything else is
    /// an error listing the options.
    pub fn choice<T: Copy>(&self, key: &str, default: T, options: &[(&str, T)]) -> Result<T, BuildError> {
        let Some(raw) = self.values.get(key) else { return Ok(default) };
        options.iter().find(|(name, _)| name == raw).map(|&(_, v)| v).ok_or_else(|| BuildError::BadParam {
            key: key.into(),
            detail: format!(
                "'{raw}' is not one of {}",
                options.iter().map(|(name, _)| *name).collect::<Vec<_>>().join(", ")
            ),
        })
    }

    /// A copy with `key` set to `value` (a sweep over one parameter).
    pub fn with(&self, key: &str, value: impl ToString) -> Self {
        let mut values = self.values.clone();
        values.insert(key.to_string(), value.to_string());
        Self { values }
    }

    pub fn iter(&self) -> impl Iterator<Item = (&str, &str)> {
        self.values.iter().map(|(k, v)| (k.as_str(), v.as_str()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_values_and_defaults() -> Result<(), BuildError> {
        let p = Params::parse(["lambda=5", " gamma = 16 "])?;
        assert_eq!(p.get("lambda", 1.0f32)?, 5.0);
        assert_eq!(p.get("gamma", 0u32)?, 16);
        assert_eq!(p.get("alpha", 2.0f32)?, 2.0);
        Ok(())
    }

    #[test]
    fn rejects_items_without_equals_and_bad_numbers() {
        assert!(Params::parse(["lambda"]).is_err());
        let p = Params::parse(["lambda=abc"]).expect("parses as text");
        let err = p.get("lambda", 1.0f32).expect_err("abc is not a number").to_string();
        assert!(err.contains("lambda") && err.contains("abc"), "{err}");
    }
}
