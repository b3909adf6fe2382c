//! Command-line parsing of the core's option enums ([`Named`]: `--reuse`, `--aov`, ...): their
//! values and aliases, and the `--help` line of each value, as clap's `ValueEnum` derive made
//! them (a value's help is the first paragraph of its doc comment, its lines joined, without
//! the final period).

use std::ffi::OsStr;
use std::marker::PhantomData;

use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use dormant::names::Named;

/// The value parser of a [`Named`] enum: `#[arg(value_parser = named::<ReuseMode>())]`. A value
/// that is none of the names is an error listing them.
pub(crate) fn named<T: Named + Send + Sync>() -> NamedParser<T> {
    NamedParser(PhantomData)
}

/// See [`named`].
#[derive(Clone, Copy)]
pub(crate) struct NamedParser<T>(PhantomData<T>);

impl<T: Named + Send + Sync> TypedValueParser for NamedParser<T> {
    type Value = T;

    fn parse_ref(
        &self,
        cmd: &clap::Command,
        arg: Option<&clap::Arg>,
        value: &OsStr,
    ) -> Result<T, clap::Error> {
        let name = PossibleValuesParser::new(possible_values::<T>()).parse_ref(cmd, arg, value)?;
        Ok(T::from_name(&name).expect("the parser accepts the values' names only"))
    }

    fn possible_values(&self) -> Option<Box<dyn Iterator<Item = PossibleValue> + '_>> {
        Some(Box::new(possible_values::<T>()))
    }
}

/// Each value with its aliases, which its help names (clap lists no aliases).
fn possible_values<T: Named>() -> impl Iterator<Item = PossibleValue> {
    T::VALUES.iter().map(|&v| {
        let value = PossibleValue::new(v.name()).aliases(v.aliases().iter().copied());
        let aliases = match v.aliases() {
            [] => None,
            names => Some(format!("also `{}`", names.join("`, `"))),
        };
        match (help(v.doc()), aliases) {
            (Some(help), Some(aliases)) => value.help(format!("{help} ({aliases})")),
            (Some(help), None) => value.help(help),
            (None, Some(aliases)) => value.help(aliases),
            (None, None) => value,
        }
    })
}

/// The help clap's derive takes from a doc comment (`///` lines): its first paragraph, each line
/// trimmed and joined by spaces, a single final period removed; `None` without a doc comment.
fn help(doc: &str) -> Option<String> {
    let blank = |l: &&str| l.trim().is_empty();
    let lines: Vec<&str> = doc.lines().skip_while(blank).take_while(|l| !blank(l)).map(str::trim).collect();
    if lines.is_empty() {
        return None;
    }
    let mut help = lines.join(" ");
    if help.ends_with('.') && !help.ends_with("..") {
        help.pop();
    }
    Some(help)
}

#[cfg(test)]
mod tests {
    use super::help;

    #[test]
    fn help_is_the_first_paragraph_without_its_period() {
        assert_eq!(help(""), None);
        assert_eq!(help(" One line.\n").as_deref(), Some("One line"));
        assert_eq!(help(" First\n continued.\n\n Second.\n").as_deref(), Some("First continued"));
        assert_eq!(help(" Ends in dots...\n").as_deref(), Some("Ends in dots..."));
    }
}
