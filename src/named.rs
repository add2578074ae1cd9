//! Options with a stable name: how the enums of configs are spelled on the command line, in
//! JSON reports and in printed tables, from one list per enum.
//!
//! The CLI builds its value parsers from these lists, so the layers below it never see clap.

/// An enum whose variants users name.
pub trait Named: Copy + Eq + Send + Sync + 'static {
    /// Every variant, in the order `--help` lists them.
    const ALL: &'static [Self];

    /// The variant's name, as typed on the command line and written in reports.
    fn name(self) -> &'static str;

    /// One line on what the variant does, for `--help`.
    fn help(self) -> &'static str;
}
