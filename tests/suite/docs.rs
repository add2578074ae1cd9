//! The results pages agree with themselves: every figure that README.md quotes is a figure of
//! BENCHMARKS.md, and both stay short enough to read.

use std::path::Path;

fn read(name: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(name);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The text outside fenced code blocks (commands and their flags are not figures).
fn prose(markdown: &str) -> String {
    let mut inside = false;
    let mut out = String::new();
    for line in markdown.lines() {
        if line.trim_start().starts_with("```") {
            inside = !inside;
        } else if !inside {
            out.push_str(line);
            out.push('\n');
        }
    }
    out
}

/// The measured figures in `text`: fractions (`84/90`), percentages (`93.3 %`), times (`0.40 s`,
/// `12 min`) and spreads (`14.2 ± 0.9`), each as written.
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
    let mut found = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let starts = chars[i].is_ascii_digit()
            && (i == 0 || !chars[i - 1].is_alphanumeric() && chars[i - 1] != '.');
        if !starts {
            i += 1;
            continue;
        }
        let end = number_at(i);
        let mut figure_end = None;
        if end < chars.len() && chars[end] == '/' && number_at(end + 1) > end + 1 {
            figure_end = Some(number_at(end + 1));
        } else if rest(end, " ± ") && number_at(end + 3) > end + 3 {
            figure_end = Some(number_at(end + 3));
        } else {
            for unit in [" %", " s", " min"] {
                let after = end + unit.chars().count();
                if rest(end, unit) && (after == chars.len() || !chars[after].is_alphanumeric()) {
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

#[test]
fn the_figure_finder_finds_fractions_rates_times_and_spreads() {
    let text = "test 84/90 = 93.3 % in 0.40 s, 14.2 ± 0.9 moved, 12 min; not 30 epochs, v0.26 or 128 × 128.";
    assert_eq!(
        figures(text),
        ["84/90", "93.3 %", "0.40 s", "14.2 ± 0.9", "12 min"]
    );
}

#[test]
fn every_figure_in_the_readme_is_a_figure_of_benchmarks_md() {
    let benchmarks = read("BENCHMARKS.md");
    let readme = prose(&read("README.md"));
    let quoted = figures(&readme);
    assert!(quoted.len() >= 10, "README.md quotes only {quoted:?}");
    let missing: Vec<&String> = quoted
        .iter()
        .filter(|f| !benchmarks.contains(f.as_str()))
        .collect();
    assert!(
        missing.is_empty(),
        "README.md quotes figures that BENCHMARKS.md does not hold: {missing:?}; quote the row instead"
    );
}

#[test]
fn the_results_pages_stay_short_with_the_results_first() {
    let benchmarks = read("BENCHMARKS.md");
    let readme = read("README.md");
    assert!(
        benchmarks.lines().count() <= 300,
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
