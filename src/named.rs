//! Options with a stable name: how the enums of configs are spelled on the command line, in
//! JSON reports and in printed tables, from one list per enum; and how counts are spelled.
//!
//! The CLI builds its value parsers from these lists, so the layers below it never see the argument parser.

/// An enum whose variants users name.
pub(crate) trait Named: Copy + Eq + Send + Sync + 'static {
    /// Every variant, in the order `--help` lists them.
    const ALL: &'static [Self];

    /// The variant's name, as typed on the command line and written in reports.
    fn name(self) -> &'static str;

    /// One line on what the variant does, for `--help`.
    fn help(self) -> &'static str;
}

/// Declares a [`Named`] enum: each variant with its doc comment, its name and its `--help`
/// line, in one row. It derives the usual traits, serialises as the name and displays as it.
macro_rules! named_enum {
    (
        $(#[$meta:meta])*
        $vis:vis enum $enum:ident {
            $(
                $(#[$variant_meta:meta])*
                $variant:ident = $name:literal, $help:literal,
            )+
        }
    ) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
        $vis enum $enum {
            $(
                $(#[$variant_meta])*
                #[serde(rename = $name)]
                $variant,
            )+
        }

        impl $crate::named::Named for $enum {
            const ALL: &'static [Self] = &[$(Self::$variant),+];

            fn name(self) -> &'static str {
                match self {
                    $(Self::$variant => $name,)+
                }
            }

            fn help(self) -> &'static str {
                match self {
                    $(Self::$variant => $help,)+
                }
            }
        }

        impl std::fmt::Display for $enum {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str($crate::named::Named::name(*self))
            }
        }
    };
}
pub(crate) use named_enum;

/// A path or value as one shell word, so that a printed command runs as printed: as it is when
/// the shell would leave it alone, else in single quotes.
pub(crate) fn shell_word(text: &str) -> String {
    let plain = !text.is_empty()
        && text
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "_-./,:=+@%".contains(c));
    match plain {
        true => text.to_owned(),
        false => format!("'{}'", text.replace('\'', r"'\''")),
    }
}

/// "1 label", "2 labels": a count and its noun, plural unless the count is one.
pub(crate) fn counted(n: usize, noun: &str) -> String {
    if n == 1 {
        format!("1 {noun}")
    } else {
        format!("{n} {noun}s")
    }
}

#[cfg(test)]
mod tests {
    use super::shell_word;

    #[test]
    fn shell_words_quote_only_what_the_shell_would_split_or_expand() {
        assert_eq!(shell_word("data/run-1.json"), "data/run-1.json");
        assert_eq!(shell_word("my data"), "'my data'");
        assert_eq!(shell_word("it's"), r"'it'\''s'");
        assert_eq!(shell_word("$HOME"), "'$HOME'");
        assert_eq!(shell_word(""), "''");
    }
}
