//! Build parameters given on the command line as `key=value` pairs (e.g. `lambda=5`,
//! `bvh.preset=fast`), parsed by each builder with its own defaults.

use std::collections::{BTreeMap, BTreeSet};
use std::str::FromStr;
use std::sync::{Arc, Mutex};

use crate::BuildError;

#[derive(Clone, Debug, Default)]
pub struct Params {
    values: BTreeMap<String, String>,
    /// Every key a builder asked for (shared by clones), so tests can check that the keys a
    /// structure declares (`kernels::StructureEntry::params`) are the keys it reads.
    reads: Arc<Mutex<BTreeSet<String>>>,
}

impl PartialEq for Params {
    fn eq(&self, other: &Self) -> bool {
        self.values == other.values
    }
}

impl Params {
    /// Parses `key=value` items; an item without `=` is an error naming it.
    pub fn parse<'a>(items: impl IntoIterator<Item = &'a str>) -> Result<Self, BuildError> {
        let mut values = BTreeMap::new();
        for item in items {
            let (k, v) = item
                .split_once('=')
                .ok_or_else(|| BuildError::BadParam { key: item.to_string(), detail: "expected key=value".into() })?;
            let key = k.trim();
            if key.is_empty() {
                return Err(BuildError::BadParam {
                    key: item.to_string(),
                    detail: "the key before '=' is empty".into(),
                });
            }
            values.insert(key.to_string(), v.trim().to_string());
        }
        Ok(Self { values, reads: Arc::default() })
    }

    fn note_read(&self, key: &str) {
        // A poisoned lock only loses the record of reads, which nothing but tests looks at.
        if let Ok(mut reads) = self.reads.lock() {
            reads.insert(key.to_string());
        }
    }

    /// The keys builders have asked for so far, given or not.
    pub fn keys_read(&self) -> BTreeSet<String> {
        self.reads.lock().map(|r| r.clone()).unwrap_or_default()
    }

    /// Checks every given key against `known` (each key with the structure that reads it).
    /// A key no structure reads is an error naming the closest known key and listing them all;
    /// a key read only by structures outside `in_run` comes back as a warning.
    pub fn check_keys(&self, known: &[(&str, &str)], in_run: &[&str]) -> Result<Vec<String>, BuildError> {
        let mut warnings = Vec::new();
        for key in self.values.keys() {
            let owners: Vec<&str> = known.iter().filter(|(k, _)| k == key).map(|&(_, s)| s).collect();
            if owners.is_empty() {
                let mut names: Vec<&str> = known.iter().map(|&(k, _)| k).collect();
                names.sort_unstable();
                names.dedup();
                let closest = names
                    .iter()
                    .map(|k| (strsim::damerau_levenshtein(key, k), *k))
                    .min()
                    .filter(|&(d, k)| d <= 2.max(k.len() / 4));
                let hint = closest.map(|(_, k)| format!("did you mean '{k}'? ")).unwrap_or_default();
                return Err(BuildError::BadParam {
                    key: key.clone(),
                    detail: format!("no structure reads this key; {hint}valid keys: {}", names.join(", ")),
                });
            }
            if !owners.iter().any(|o| in_run.contains(o)) {
                warnings.push(format!(
                    "parameter '{key}' is read only by {}, which {} not in this run",
                    owners.join(", "),
                    if owners.len() == 1 { "is" } else { "are" }
                ));
            }
        }
        Ok(warnings)
    }

    /// The value of `key` parsed as `T`, or `default` when absent.
    pub fn get<T: FromStr>(&self, key: &str, default: T) -> Result<T, BuildError>
    where
        T::Err: std::fmt::Display,
    {
        self.note_read(key);
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
        self.note_read(key);
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
        Self { values, reads: Arc::default() }
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
        assert!(Params::parse(["=5"]).is_err(), "an empty key is an error");
    }

    #[test]
    fn unknown_keys_are_rejected_with_a_suggestion_and_foreign_keys_warned() {
        let known = [("org.lambda", "org"), ("ug.lambda", "ug"), ("voxel.levels", "esvo"), ("voxel.levels", "svo")];
        let misspelt = Params::parse(["org.lamda=2"]).expect("parses");
        let err = misspelt.check_keys(&known, &["org"]).expect_err("org.lamda is unknown").to_string();
        assert!(err.contains("did you mean 'org.lambda'") && err.contains("ug.lambda"), "{err}");
        let far = Params::parse(["colour=red"]).expect("parses");
        let err = far.check_keys(&known, &["org"]).expect_err("colour is unknown").to_string();
        assert!(!err.contains("did you mean") && err.contains("valid keys"), "{err}");
        let foreign = Params::parse(["ug.lambda=3", "voxel.levels=8"]).expect("parses");
        let warnings = foreign.check_keys(&known, &["org", "svo"]).expect("known keys");
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        assert!(warnings[0].contains("'ug.lambda'") && warnings[0].contains("ug, which is not"), "{warnings:?}");
    }

    #[test]
    fn reads_are_recorded() {
        let p = Params::parse(["a=1"]).expect("parses");
        let _ = p.get("a", 0u32);
        let _ = p.choice("b", 0, &[("x", 1)]);
        assert_eq!(p.keys_read().into_iter().collect::<Vec<_>>(), ["a", "b"]);
    }
}
