//! Which flags the user typed, as opposed to those holding their defaults: a flag that does not
//! apply to the run that the other flags choose (`eval --task train --give-up-after 3`,
//! `collect --policy oracle --explore 0.9`) is refused when typed, while its default stays
//! harmless. clap's own `conflicts_with` and `requires` cover the combinations that do not
//! depend on a flag's value.

use clap::parser::ValueSource;
use clap::ArgMatches;

/// The matches of the command that runs (the innermost subcommand).
#[derive(Debug, Default)]
pub(crate) struct Given(Option<ArgMatches>);

impl Given {
    /// The innermost subcommand's matches of a whole command line.
    pub(crate) fn of(matches: &ArgMatches) -> Self {
        let mut inner = matches;
        while let Some((_, sub)) = inner.subcommand() {
            inner = sub;
        }
        Given(Some(inner.clone()))
    }

    /// Whether the flag with this id (the field's name) was typed.
    pub(crate) fn has(&self, id: &str) -> bool {
        let Some(matches) = &self.0 else {
            return false;
        };
        debug_assert!(
            matches.try_contains_id(id).is_ok(),
            "no flag with the id {id}"
        );
        matches.try_contains_id(id).unwrap_or(false)
            && matches.value_source(id) == Some(ValueSource::CommandLine)
    }

    /// The first of `ids` that was typed, as its flag is spelled (`--give-up-after`).
    pub(crate) fn first_of(&self, ids: &[&str]) -> Option<String> {
        ids.iter()
            .find(|id| self.has(id))
            .map(|id| format!("--{}", id.replace('_', "-")))
    }
}

/// Refuses the first typed flag of `ids`, global flags that `command` never reads.
pub(crate) fn refuse_unread(given: &Given, command: &str, ids: &[&str]) -> anyhow::Result<()> {
    if let Some(flag) = given.first_of(ids) {
        anyhow::bail!("{flag} is not used by `graspmap {command}`; leave it out");
    }
    Ok(())
}

/// Refuses the first typed flag of `ids`, which applies only to `applies_to` while this run is
/// `this_run` (both as flags would spell them, e.g. "--task empty_bin").
pub(crate) fn refuse_inapplicable(
    given: &Given,
    ids: &[&str],
    applies_to: &str,
    this_run: &str,
) -> anyhow::Result<()> {
    if let Some(flag) = given.first_of(ids) {
        anyhow::bail!(
            "{flag} applies to {applies_to} only, and this run is {this_run}; leave it out"
        );
    }
    Ok(())
}
