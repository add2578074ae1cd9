//! The results pages agree with themselves: every measured figure that README.md or a page of
//! docs/ quotes stands beside a link to the section of BENCHMARKS.md that holds it, every link to
//! a heading resolves, and the results pages stay short enough to read.

use std::collections::BTreeSet;
use std::path::Path;

fn read(name: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(name);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The pages of docs/, as paths from the repository root, in name order.
fn doc_pages() -> Vec<String> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs");
    let mut pages: Vec<String> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|entry| entry.expect("reading docs/").file_name())
        .filter_map(|name| name.to_str().map(str::to_string))
        .filter(|name| name.ends_with(".md"))
        .map(|name| format!("docs/{name}"))
        .collect();
    pages.sort();
    pages
}

/// The text outside code blocks, fenced or indented (commands, file layouts and sample output
/// are not figures); code lines become blank lines, so paragraphs keep their boundaries.
fn prose(markdown: &str) -> String {
    let mut fenced = false;
    let mut indented = false;
    let mut previous_blank = true;
    let mut out = String::new();
    for line in markdown.lines() {
        let blank = line.trim().is_empty();
        let fence = line.trim_start().starts_with("```");
        if fence {
            fenced = !fenced;
        }
        let code = fence
            || fenced
            || (!blank
                && (line.starts_with("    ") || line.starts_with('\t'))
                && (previous_blank || indented));
        if !blank {
            indented = code && !fence && !fenced;
        }
        previous_blank = blank;
        if !code {
            out.push_str(line);
        }
        out.push('\n');
    }
    out
}

/// Where a figure stands, with the links that name its source: each paragraph, list item and
/// heading, and each table row together with its table's header (whose links name what every
/// row measures). Lines are joined with spaces, so a figure wrapped over two lines is whole.
fn passages(prose: &str) -> Vec<String> {
    let mut passages = Vec::new();
    let mut current: Vec<&str> = Vec::new();
    let mut header: Option<&str> = None;
    let flush = |current: &mut Vec<&str>, passages: &mut Vec<String>| {
        if !current.is_empty() {
            passages.push(current.join(" "));
            current.clear();
        }
    };
    for line in prose.lines().map(str::trim) {
        if line.is_empty() {
            flush(&mut current, &mut passages);
            header = None;
        } else if line.starts_with('|') {
            flush(&mut current, &mut passages);
            match header {
                None => header = Some(line),
                Some(_) if line.chars().all(|c| "|-: ".contains(c)) => {}
                Some(head) => passages.push(format!("{head} {line}")),
            }
        } else {
            header = None;
            let item = line.starts_with("- ")
                || line.starts_with("* ")
                || line.starts_with('#')
                || line
                    .split_once(". ")
                    .is_some_and(|(n, _)| !n.is_empty() && n.chars().all(|c| c.is_ascii_digit()));
            if item {
                flush(&mut current, &mut passages);
            }
            current.push(line);
        }
    }
    flush(&mut current, &mut passages);
    passages
}

/// `text` without what is not read as prose: inline code (flags, commands, sample lines), link
/// targets and HTML tags.
fn readable(text: &str) -> String {
    let mut out = String::new();
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '`' => {
                for d in chars.by_ref() {
                    if d == '`' {
                        break;
                    }
                }
            }
            '<' => {
                for d in chars.by_ref() {
                    if d == '>' {
                        break;
                    }
                }
            }
            ']' if chars.peek() == Some(&'(') => {
                out.push(']');
                for d in chars.by_ref() {
                    if d == ')' {
                        break;
                    }
                }
            }
            _ => out.push(c),
        }
    }
    out
}

/// The measured figures in `text`: fractions (`84/90`), percentages (`93.3 %`), times (`0.40 s`,
/// `12 min`, `94 ms`), sizes (`1.62 MiB`), speed-ups (`2.8× faster`, as `2.8×`) and spreads
/// (`14.2 ± 0.9`), each as written. A chain such as `0/1000/2000` is a list of seeds, and
/// `1 s⁻¹` a unit of damping, not figures.
fn figures(text: &str) -> Vec<String> {
    let chars: Vec<char> = text.chars().collect();
    let number_at = |i: usize| -> usize {
        let mut j = i;
        while j < chars.len() && (chars[j].is_ascii_digit() || (chars[j] == '.' && j > i)) {
            j += 1;
        }
        if j > i && chars[j - 1] == '.' {
            j - 1
        } else {
            j
        }
    };
    let rest = |i: usize, s: &str| {
        chars[i..]
            .iter()
            .take(s.chars().count())
            .collect::<String>()
            == s
    };
    let ends_word = |i: usize| i == chars.len() || !(chars[i].is_alphanumeric() || chars[i] == '⁻');
    let mut found = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let starts = chars[i].is_ascii_digit()
            && (i == 0 || !chars[i - 1].is_alphanumeric() && !".,/".contains(chars[i - 1]));
        if !starts {
            i += 1;
            continue;
        }
        let end = number_at(i);
        let mut figure_end = None;
        if end < chars.len() && chars[end] == '/' && number_at(end + 1) > end + 1 {
            let stop = number_at(end + 1);
            if !rest(stop, "/") {
                figure_end = Some(stop);
            }
        } else if rest(end, " ± ") && number_at(end + 3) > end + 3 {
            figure_end = Some(number_at(end + 3));
        } else if (rest(end, "×") || rest(end, "x"))
            && (rest(end + 1, " faster") || rest(end + 1, " slower"))
        {
            figure_end = Some(end + 1);
        } else {
            for unit in [" %", " s", " min", " ms", " MB", " MiB", " GB"] {
                let after = end + unit.chars().count();
                if rest(end, unit) && ends_word(after) {
                    figure_end = Some(after);
                }
            }
        }
        if let Some(stop) = figure_end {
            found.push(chars[i..stop].iter().collect());
            i = stop;
        } else {
            i = end.max(i + 1);
        }
    }
    found
}

/// The anchor GitHub gives a heading: lower case, spaces as hyphens, other punctuation (dashes
/// and × included) dropped.
fn anchor_of(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
            _ => None,
        })
        .collect()
}

/// One heading's section of a page: its anchors (GitHub's, numbered when repeated, and any
/// `<a id>` in it), its heading and its text with whitespace collapsed.
struct Section {
    anchors: Vec<String>,
    heading: String,
    text: String,
}

fn sections(markdown: &str) -> Vec<Section> {
    let mut sections = vec![Section {
        anchors: Vec::new(),
        heading: "(the page's top)".to_string(),
        text: String::new(),
    }];
    let mut seen: Vec<String> = Vec::new();
    let mut fenced = false;
    for line in markdown.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
        }
        let heading = line.trim_start_matches('#');
        if !fenced && line.starts_with('#') && heading.starts_with(' ') {
            let anchor = anchor_of(heading);
            let repeats = seen.iter().filter(|a| **a == anchor).count();
            seen.push(anchor.clone());
            let anchor = if repeats == 0 {
                anchor
            } else {
                format!("{anchor}-{repeats}")
            };
            sections.push(Section {
                anchors: vec![anchor],
                heading: heading.trim().to_string(),
                text: String::new(),
            });
        }
        let section = sections.last_mut().expect("the top section");
        let mut rest = line;
        while let Some(start) = rest.find("<a id=\"") {
            let id = &rest[start + 7..];
            let end = id.find('"').unwrap_or(id.len());
            section.anchors.push(id[..end].to_string());
            rest = &id[end..];
        }
        section.text.push(' ');
        section.text.push_str(line);
    }
    for section in &mut sections {
        section.text = section
            .text
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ");
    }
    sections
}

/// The anchors of BENCHMARKS.md that `passage` links to, in order.
fn benchmarks_links(passage: &str) -> Vec<String> {
    passage
        .split("BENCHMARKS.md#")
        .skip(1)
        .map(|after| {
            after
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '-' || *c == '_')
                .collect()
        })
        .collect()
}

/// Figures in docs/ that are settings, not measurements: times and shares the code is written
/// with (settle windows, a split, a tolerance, a confidence level), which no BENCHMARKS.md row
/// holds. A new entry here must be a constant of the code, never a measured result.
const SETTINGS: &[(&str, &[&str])] = &[
    (
        "docs/departures.md",
        &["0.25 s", "4 s", "10 %", "1/240", "95 %"],
    ),
    ("docs/design.md", &["0.25 s", "4 s", "32 MiB"]),
    ("docs/evaluation.md", &["95 %", "0 %", "100 %"]),
    ("docs/grasping.md", &["0.25 s", "0.6 s", "1 s", "2 s"]),
    ("docs/learning.md", &["20 %", "90/10"]),
    ("docs/usage.md", &["20 %", "90/10", "95 %"]),
    ("docs/workcell.md", &["0.25 s", "4 s", "10 %"]),
];

/// What is wrong with the figures `page` quotes in `markdown`: a measured figure must stand in a
/// passage that links to a section of BENCHMARKS.md holding that same figure, so that a figure
/// remeasured there and forgotten here, or quoted from the wrong table, fails. Returns the
/// figures checked and one line per problem, naming the page, the figure and the section.
fn figure_problems(
    page: &str,
    markdown: &str,
    benchmarks: &[Section],
    settings: &[&str],
) -> (usize, Vec<String>) {
    let mut checked = 0;
    let mut problems = Vec::new();
    for passage in passages(&prose(markdown)) {
        let quoted: Vec<String> = figures(&readable(&passage))
            .into_iter()
            .filter(|f| !settings.contains(&f.as_str()))
            .collect();
        if quoted.is_empty() {
            continue;
        }
        checked += quoted.len();
        let excerpt: String = passage.chars().take(90).collect();
        let mut linked: Vec<&Section> = benchmarks_links(&passage)
            .iter()
            .filter_map(|a| benchmarks.iter().find(|s| s.anchors.contains(a)))
            .collect();
        linked.dedup_by_key(|s| s.heading.clone());
        for figure in quoted {
            let holds = |s: &&Section| s.text.contains(&figure.replace('x', "×"));
            if linked.is_empty() {
                problems.push(format!(
                    "{page}: \"{figure}\" (in \"{excerpt}…\") has no link to the BENCHMARKS.md \
                     section that holds it; link the row instead of quoting it (a constant of \
                     the code goes in SETTINGS, tests/suite/docs.rs)"
                ));
            } else if !linked.iter().any(holds) {
                let headings: Vec<&str> = linked.iter().map(|s| s.heading.as_str()).collect();
                problems.push(format!(
                    "{page}: \"{figure}\" (in \"{excerpt}…\") is not in BENCHMARKS.md's section \
                     {headings:?}, which the passage links to"
                ));
            }
        }
    }
    (checked, problems)
}

#[test]
fn the_figure_finder_finds_fractions_rates_times_sizes_speedups_and_spreads() {
    let text = "test 84/90 = 93.3 % in 0.40 s, 14.2 ± 0.9 moved, 12 min, 94 ms, 1.62 MiB, 2.8× \
                faster; not 30 epochs, v0.26, 128 × 128, seeds 0/1000/2000, 1 s⁻¹ or at 2× size.";
    assert_eq!(
        figures(text),
        [
            "84/90",
            "93.3 %",
            "0.40 s",
            "14.2 ± 0.9",
            "12 min",
            "94 ms",
            "1.62 MiB",
            "2.8×"
        ]
    );
}

#[test]
fn a_figure_that_benchmarks_md_does_not_hold_for_the_same_measure_fails() {
    let benchmarks = sections(
        "# Benchmarks\n## Training\n| bf16 | **15.0 s** |\n## Labelling\n| 60 (60) | 14.9 s |\n",
    );
    let page = |text: &str| figure_problems("docs/x.md", text, &benchmarks, &["0.25 s"]);
    let linked = "Training takes 15.0 s ([training](../BENCHMARKS.md#training)).";
    assert_eq!(page(linked), (1, vec![]));
    let (_, stale) = page("Training takes 13.2 s ([training](../BENCHMARKS.md#training)).");
    assert!(
        stale.len() == 1
            && stale[0].contains("docs/x.md: \"13.2 s\"")
            && stale[0].contains("Training"),
        "{stale:?}"
    );
    let (_, elsewhere) = page("Training takes 14.9 s ([training](../BENCHMARKS.md#training)).");
    assert_eq!(
        elsewhere.len(),
        1,
        "a figure of another section: {elsewhere:?}"
    );
    let (_, unlinked) = page("Training takes 15.0 s.");
    assert!(
        unlinked.len() == 1 && unlinked[0].contains("no link"),
        "{unlinked:?}"
    );
    assert_eq!(
        page("Objects settle for 0.25 s.\n\n    sample 9.9 s\n"),
        (0, vec![])
    );
}

#[test]
fn every_measured_figure_in_readme_and_docs_is_one_of_its_linked_benchmarks_section() {
    let benchmarks = sections(&read("BENCHMARKS.md"));
    let (in_readme, mut problems) =
        figure_problems("README.md", &read("README.md"), &benchmarks, &[]);
    assert!(in_readme >= 10, "README.md quotes only {in_readme} figures");
    for page in doc_pages() {
        let settings = SETTINGS
            .iter()
            .find(|(name, _)| *name == page)
            .map_or(&[][..], |(_, figures)| *figures);
        problems.extend(figure_problems(&page, &read(&page), &benchmarks, settings).1);
    }
    assert!(
        problems.is_empty(),
        "measured figures must live in BENCHMARKS.md (README's tables quote them beside a link to \
         their section):\n{}",
        problems.join("\n")
    );
}

#[test]
fn every_link_to_a_heading_resolves() {
    let mut pages = vec![
        "README.md".to_string(),
        "BENCHMARKS.md".to_string(),
        "CHANGELOG.md".to_string(),
    ];
    pages.extend(doc_pages());
    let mut dead = Vec::new();
    for page in &pages {
        let markdown = read(page);
        for link in markdown.split("](").skip(1) {
            let target = link.split(')').next().unwrap_or_default();
            let Some((file, anchor)) = target.split_once('#') else {
                continue;
            };
            if file.contains("://") || !(file.is_empty() || file.ends_with(".md")) {
                continue;
            }
            let linked = if file.is_empty() {
                page.clone()
            } else {
                let mut parts: Vec<&str> = page.split('/').collect();
                parts.pop();
                for part in file.split('/') {
                    match part {
                        ".." => {
                            parts.pop();
                        }
                        "." => {}
                        _ => parts.push(part),
                    }
                }
                parts.join("/")
            };
            let anchors: BTreeSet<String> = sections(&read(&linked))
                .into_iter()
                .flat_map(|s| s.anchors)
                .collect();
            if !anchors.contains(anchor) {
                dead.push(format!(
                    "{page}: ({target}) has no heading #{anchor} in {linked}"
                ));
            }
        }
    }
    assert!(dead.is_empty(), "dead links:\n{}", dead.join("\n"));
}

#[test]
fn the_results_pages_stay_short_with_the_results_first() {
    let benchmarks = read("BENCHMARKS.md");
    let readme = read("README.md");
    assert!(
        benchmarks.lines().count() <= 380,
        "BENCHMARKS.md has {} lines",
        benchmarks.lines().count()
    );
    assert!(
        readme.lines().count() <= 200,
        "README.md has {} lines",
        readme.lines().count()
    );
    let results = readme
        .lines()
        .position(|l| l.starts_with("| task"))
        .expect("README.md has no results table");
    assert!(
        results < 60,
        "README.md's results table starts on line {}",
        results + 1
    );
}
