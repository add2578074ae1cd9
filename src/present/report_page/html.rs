//! HTML text for the report page: escaping, and the line that names what is missing.

/// Escapes text for HTML content and attribute values.
pub(crate) fn esc(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// A command the page suggests, spelled to run as printed from anywhere: `graspmap --data
/// DATA <rest>`, the run's data directory quoted for the shell.
pub(crate) fn command(data: &std::path::Path, rest: &str) -> String {
    let data = crate::named::shell_word(&data.display().to_string());
    format!("graspmap --data {data} {rest}")
}

/// A line saying what is missing and which command makes it.
pub(crate) fn missing(what: &str, command: &str) -> String {
    format!(
        "<p class=\"missing\">{}: run <code>{}</code>.</p>\n",
        esc(what),
        esc(command)
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escaping_covers_markup_and_quotes() {
        assert_eq!(
            esc("<a href=\"x\">'&'</a>"),
            "&lt;a href=&quot;x&quot;&gt;&#39;&amp;&#39;&lt;/a&gt;"
        );
    }
}
