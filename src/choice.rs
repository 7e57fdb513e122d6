//! Command-line values that name a library enum (a sampling method, a PSD model, an export
//! format). The library parses the names (`FromStr`) and lists them; clap only shows and checks.

use clap::builder::{PossibleValuesParser, TypedValueParser};

/// A parser accepting exactly `names`, each turned into `T` by its `FromStr`.
pub fn choice<T>(names: impl IntoIterator<Item = &'static str>) -> impl TypedValueParser<Value = T>
where
    T: std::str::FromStr + Clone + Send + Sync + 'static,
    T::Err: std::error::Error + Send + Sync + 'static,
{
    PossibleValuesParser::new(names).try_map(|s| s.parse::<T>())
}
