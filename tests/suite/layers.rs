//! The layers of src/, checked against the table in src/lib.rs's module doc.
//!
//! The table (`| layer | modules | may use |`) is the single source of truth. This file reads
//! every `.rs` file under src/, keeps its non-test code (items under `#[cfg(test)]`, and files
//! whose `mod` is declared under it, are skipped), and collects every path into another module:
//! `use crate::…` (grouped ones included, over any number of lines), `crate::…`, `super::…` and
//! `self::…` in code, and paths that start with a child module's name (`use child::…`). Then:
//!
//! - every module src/lib.rs declares is in exactly one layer, and every module of the table
//!   exists;
//! - every path from one top-level module into another stays in its layer or goes to a layer
//!   its row may use;
//! - no module below `commands` imports `crate::commands`;
//! - no files import each other in a cycle: a path `crate::a::b::c` points at the deepest file
//!   that exists (src/a/b.rs or src/a/b/mod.rs, …), `super::` at the parent module's file.
//!   `mod x;` alone is no edge.
//!
//! Only std: the logic can be checked on its own, without the crate compiling:
//! `rustc --edition 2021 --test tests/suite/layers.rs -o /tmp/layers && /tmp/layers`
//! from the repository root.

use std::collections::{BTreeMap, BTreeSet, VecDeque};
use std::path::Path;

// ----------------------------------------------------------------------------------------------
// The table.

/// One row of the table.
#[derive(Debug, Clone, PartialEq)]
struct Layer {
    name: String,
    modules: Vec<String>,
    may_use: Vec<String>,
    /// 1-based line in src/lib.rs.
    line: usize,
}

/// The rows of the `| layer | modules | may use |` table in a `//!` doc.
fn parse_table(lib: &str) -> Result<Vec<Layer>, String> {
    let cells = |line: &str| -> Option<Vec<String>> {
        let row = line.trim_start().strip_prefix("//!")?.trim();
        let inner = row.strip_prefix('|')?.strip_suffix('|')?;
        Some(inner.split('|').map(|c| c.trim().to_owned()).collect())
    };
    let names = |cell: &str| -> Vec<String> {
        cell.split(',')
            .map(|n| {
                n.trim()
                    .trim_matches(|c| matches!(c, '`' | '[' | ']'))
                    .to_owned()
            })
            .filter(|n| !n.is_empty())
            .collect()
    };
    let lines: Vec<&str> = lib.lines().collect();
    let header = lines
        .iter()
        .position(|l| cells(l).is_some_and(|c| c == ["layer", "modules", "may use"]))
        .ok_or("src/lib.rs has no `//! | layer | modules | may use |` table")?;
    let mut layers = Vec::new();
    for (i, line) in lines.iter().enumerate().skip(header + 1) {
        let Some(row) = cells(line) else { break };
        if row
            .iter()
            .all(|c| !c.is_empty() && c.chars().all(|ch| matches!(ch, '-' | ':')))
        {
            continue;
        }
        if row.len() != 3 {
            return Err(format!(
                "src/lib.rs:{}: a table row has {} cells, not 3: {line}",
                i + 1,
                row.len()
            ));
        }
        layers.push(Layer {
            name: row[0].trim_matches('`').to_owned(),
            modules: names(&row[1]),
            may_use: names(&row[2]),
            line: i + 1,
        });
    }
    if layers.is_empty() {
        return Err("src/lib.rs's layer table has no rows".to_owned());
    }
    Ok(layers)
}

// ----------------------------------------------------------------------------------------------
// Tokens: what the compiler sees, without comments, strings and characters.

#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    Ident,
    Punct,
    Literal,
}

#[derive(Debug, Clone, PartialEq)]
struct Token {
    kind: Kind,
    text: String,
    line: usize,
}

impl Token {
    fn is(&self, text: &str) -> bool {
        self.kind != Kind::Literal && self.text == text
    }
}

fn is_ident_start(c: char) -> bool {
    c.is_alphabetic() || c == '_'
}

fn is_ident_char(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// Splits Rust source into identifiers, `::`, single-character punctuation and literals.
/// Comments (doc comments included) are dropped; a literal's text is not kept.
fn lex(src: &str) -> Vec<Token> {
    let s: Vec<char> = src.chars().collect();
    let at = |i: usize| s.get(i).copied().unwrap_or('\0');
    let mut tokens = Vec::new();
    let mut line = 1;
    let mut i = 0;
    // Skips a quoted literal whose opening quote is at `i`; returns the index after it.
    let skip_quoted = |mut i: usize, quote: char, line: &mut usize| -> usize {
        i += 1;
        while i < s.len() && s[i] != quote {
            if s[i] == '\\' {
                i += 1;
            }
            if at(i) == '\n' {
                *line += 1;
            }
            i += 1;
        }
        i + 1
    };
    while i < s.len() {
        let c = s[i];
        let start_line = line;
        let literal = |tokens: &mut Vec<Token>| {
            tokens.push(Token {
                kind: Kind::Literal,
                text: String::new(),
                line: start_line,
            })
        };
        if c == '\n' {
            line += 1;
            i += 1;
        } else if c.is_whitespace() {
            i += 1;
        } else if c == '/' && at(i + 1) == '/' {
            while i < s.len() && s[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && at(i + 1) == '*' {
            let mut depth = 1;
            i += 2;
            while i < s.len() && depth > 0 {
                if s[i] == '/' && at(i + 1) == '*' {
                    depth += 1;
                    i += 2;
                } else if s[i] == '*' && at(i + 1) == '/' {
                    depth -= 1;
                    i += 2;
                } else {
                    if s[i] == '\n' {
                        line += 1;
                    }
                    i += 1;
                }
            }
        } else if c == '"' {
            i = skip_quoted(i, '"', &mut line);
            literal(&mut tokens);
        } else if c == '\'' {
            if at(i + 1) == '\\' {
                // '\n', '\'', '\u{..}'
                let mut j = i + 3;
                while j < s.len() && s[j] != '\'' {
                    j += 1;
                }
                i = j + 1;
                literal(&mut tokens);
            } else if at(i + 2) == '\'' {
                i += 3;
                literal(&mut tokens);
            } else {
                // A lifetime or a label.
                i += 1;
                while is_ident_char(at(i)) {
                    i += 1;
                }
            }
        } else if is_ident_start(c) {
            // Literal prefixes: b"..", b'..', c"..", r"..", r#".."#, br#".."#, and raw idents r#x.
            let mut j = i;
            if matches!(c, 'b' | 'c') {
                j += 1;
            }
            if at(j) == 'r' && matches!(at(j + 1), '#' | '"') {
                let mut k = j + 1;
                let mut hashes = 0;
                while at(k) == '#' {
                    hashes += 1;
                    k += 1;
                }
                if at(k) == '"' {
                    k += 1;
                    loop {
                        if k >= s.len() {
                            break;
                        }
                        if s[k] == '"' && (1..=hashes).all(|h| at(k + h) == '#') {
                            k += 1 + hashes;
                            break;
                        }
                        if s[k] == '\n' {
                            line += 1;
                        }
                        k += 1;
                    }
                    i = k;
                    literal(&mut tokens);
                    continue;
                }
                if j == i && hashes == 1 && is_ident_start(at(k)) {
                    i = k; // r#ident: the identifier without its prefix
                }
            } else if j > i && at(j) == '"' {
                i = skip_quoted(j, '"', &mut line);
                literal(&mut tokens);
                continue;
            } else if c == 'b' && at(i + 1) == '\'' {
                i = skip_quoted(i + 1, '\'', &mut line);
                literal(&mut tokens);
                continue;
            }
            let begin = i;
            while i < s.len() && is_ident_char(s[i]) {
                i += 1;
            }
            tokens.push(Token {
                kind: Kind::Ident,
                text: s[begin..i].iter().collect(),
                line,
            });
        } else if c.is_ascii_digit() {
            while i < s.len() && is_ident_char(s[i]) {
                i += 1;
            }
            literal(&mut tokens);
        } else if c == ':' && at(i + 1) == ':' {
            tokens.push(Token {
                kind: Kind::Punct,
                text: "::".to_owned(),
                line,
            });
            i += 2;
        } else {
            tokens.push(Token {
                kind: Kind::Punct,
                text: c.to_string(),
                line,
            });
            i += 1;
        }
    }
    tokens
}

// ----------------------------------------------------------------------------------------------
// One file: its non-test code, its `mod` declarations and its paths.

/// A `mod name;` declaration.
#[derive(Debug, Clone, PartialEq)]
struct ModDecl {
    name: String,
    /// Declared under `#[cfg(test)]`.
    test: bool,
    line: usize,
}

/// A path as written in a file's non-test code, `use` trees expanded.
#[derive(Debug, Clone, PartialEq)]
struct RawPath {
    segments: Vec<String>,
    line: usize,
    /// The inline (`mod x { … }`) modules the path sits in, outermost first.
    inline: Vec<String>,
    in_use: bool,
}

#[derive(Debug, Default)]
struct Parsed {
    mods: Vec<ModDecl>,
    paths: Vec<RawPath>,
    /// `#![cfg(test)]`: the whole file is test code.
    test_only: bool,
}

/// The index after the attribute that starts at `i` (`#[…]` or `#![…]`), and whether it is
/// `cfg(test)` (or `cfg(all(test, …))`).
fn attribute(tokens: &[Token], i: usize) -> Option<(usize, bool, bool)> {
    let inner = tokens.get(i + 1)?.is("!");
    let open = if inner { i + 2 } else { i + 1 };
    if !tokens.get(open)?.is("[") {
        return None;
    }
    let mut depth = 0;
    let mut j = open;
    while j < tokens.len() {
        if tokens[j].is("[") {
            depth += 1;
        } else if tokens[j].is("]") {
            depth -= 1;
            if depth == 0 {
                break;
            }
        }
        j += 1;
    }
    let body: Vec<&str> = tokens[open + 1..j.min(tokens.len())]
        .iter()
        .map(|t| t.text.as_str())
        .collect();
    let test = body == ["cfg", "(", "test", ")"]
        || (body.starts_with(&["cfg", "(", "all", "("])
            && body.len() > 4
            && (body[4] == "test" || body.windows(2).any(|w| w == [",", "test"])));
    Some((j + 1, inner, test))
}

/// The index after the item (or field, statement, match arm) that starts at `i`.
fn skip_item(tokens: &[Token], mut i: usize) -> usize {
    let mut depth = 0usize;
    while i < tokens.len() {
        let t = &tokens[i];
        if t.is("(") || t.is("[") {
            depth += 1;
        } else if t.is(")") || t.is("]") || t.is("}") {
            if depth == 0 {
                return i; // the end of the enclosing list or block
            }
            depth -= 1;
        } else if t.is("{") {
            if depth == 0 {
                let mut braces = 0;
                while i < tokens.len() {
                    if tokens[i].is("{") {
                        braces += 1;
                    } else if tokens[i].is("}") {
                        braces -= 1;
                        if braces == 0 {
                            break;
                        }
                    }
                    i += 1;
                }
                return i + 1;
            }
            depth += 1;
        } else if (t.is(";") || t.is(",")) && depth == 0 {
            return i + 1;
        }
        i += 1;
    }
    i
}

/// `[pub[(…)]] mod name ;` at `i`: the name and its line.
fn mod_declaration(tokens: &[Token], mut i: usize) -> Option<(String, usize)> {
    if tokens.get(i)?.is("pub") {
        i += 1;
        if tokens.get(i)?.is("(") {
            while !tokens.get(i)?.is(")") {
                i += 1;
            }
            i += 1;
        }
    }
    let name = tokens.get(i + 1)?;
    (tokens.get(i)?.is("mod") && name.kind == Kind::Ident && tokens.get(i + 2)?.is(";"))
        .then(|| (name.text.clone(), name.line))
}

/// The tokens of a file without its test code, and the `mod` declarations under `#[cfg(test)]`.
fn without_tests(tokens: &[Token]) -> (Vec<Token>, Vec<ModDecl>, bool) {
    let mut kept = Vec::new();
    let mut test_mods = Vec::new();
    let mut i = 0;
    while i < tokens.len() {
        if tokens[i].is("#") {
            if let Some((end, inner, test)) = attribute(tokens, i) {
                if test && inner {
                    return (Vec::new(), Vec::new(), true);
                }
                if test {
                    // Further attributes belong to the same item.
                    let mut item = end;
                    while tokens.get(item).is_some_and(|t| t.is("#")) {
                        match attribute(tokens, item) {
                            Some((after, _, _)) => item = after,
                            None => break,
                        }
                    }
                    if let Some((name, line)) = mod_declaration(tokens, item) {
                        test_mods.push(ModDecl {
                            name,
                            test: true,
                            line,
                        });
                    }
                    i = skip_item(tokens, item);
                    continue;
                }
                kept.extend_from_slice(&tokens[i..end]);
                i = end;
                continue;
            }
        }
        kept.push(tokens[i].clone());
        i += 1;
    }
    (kept, test_mods, false)
}

/// Expands the `use` tree at `i` into its paths (with the line of each path's last segment);
/// returns the index after the tree.
fn use_tree(
    tokens: &[Token],
    mut i: usize,
    prefix: &[String],
    out: &mut Vec<(Vec<String>, usize)>,
) -> usize {
    let mut segments = prefix.to_vec();
    if tokens.get(i).is_some_and(|t| t.is("::")) {
        segments.push("::".to_owned()); // an extern crate's path
        i += 1;
    }
    let mut emit = |mut segments: Vec<String>, line: usize| {
        if segments.last().is_some_and(|s| s == "self") {
            segments.pop();
        }
        out.push((segments, line));
    };
    while let Some(t) = tokens.get(i) {
        if t.kind == Kind::Ident {
            segments.push(t.text.clone());
            i += 1;
            if tokens.get(i).is_some_and(|t| t.is("::")) {
                i += 1;
                continue;
            }
            if tokens.get(i).is_some_and(|t| t.is("as")) {
                i += 2;
            }
            emit(segments, t.line);
            return i;
        } else if t.is("*") {
            emit(segments, t.line);
            return i + 1;
        } else if t.is("{") {
            i += 1;
            while let Some(t) = tokens.get(i) {
                if t.is("}") {
                    return i + 1;
                }
                if t.is(",") {
                    i += 1;
                    continue;
                }
                let next = use_tree(tokens, i, &segments, out);
                if next == i {
                    return i; // not a use tree: give up on it
                }
                i = next;
            }
            return i;
        } else {
            return i;
        }
    }
    i
}

/// A file's `mod` declarations and the paths of its non-test code.
fn parse_file(src: &str) -> Parsed {
    let (tokens, test_mods, test_only) = without_tests(&lex(src));
    if test_only {
        return Parsed {
            test_only,
            ..Parsed::default()
        };
    }
    let mut parsed = Parsed {
        mods: test_mods,
        ..Parsed::default()
    };
    // Child modules (`mod x;` outside inline modules) are in scope from the file's start.
    let mut depth = 0usize;
    for (i, t) in tokens.iter().enumerate() {
        if t.is("{") {
            depth += 1;
        } else if t.is("}") {
            depth = depth.saturating_sub(1);
        } else if depth == 0 && t.is("mod") {
            let (Some(name), Some(end)) = (tokens.get(i + 1), tokens.get(i + 2)) else {
                continue;
            };
            if name.kind == Kind::Ident && end.is(";") {
                parsed.mods.push(ModDecl {
                    name: name.text.clone(),
                    test: false,
                    line: name.line,
                });
            }
        }
    }
    let children: BTreeSet<&str> = parsed
        .mods
        .iter()
        .filter(|m| !m.test)
        .map(|m| m.name.as_str())
        .collect();

    let mut depth = 0usize;
    let mut inline: Vec<(String, usize)> = Vec::new();
    let mut i = 0;
    while i < tokens.len() {
        let t = &tokens[i];
        let prev = i.checked_sub(1).map(|p| &tokens[p]);
        let next = |k: usize| tokens.get(i + k);
        let stack = || inline.iter().map(|(n, _)| n.clone()).collect::<Vec<_>>();
        if t.is("{") {
            depth += 1;
        } else if t.is("}") {
            depth = depth.saturating_sub(1);
            if inline.last().is_some_and(|(_, d)| *d == depth) {
                inline.pop();
            }
        } else if t.is("mod")
            && next(1).is_some_and(|n| n.kind == Kind::Ident)
            && next(2).is_some_and(|n| n.is("{"))
        {
            inline.push((next(1).unwrap().text.clone(), depth));
            depth += 1;
            i += 3;
            continue;
        } else if t.is("use") {
            let mut trees = Vec::new();
            let end = use_tree(&tokens, i + 1, &[], &mut trees);
            for (segments, line) in trees {
                parsed.paths.push(RawPath {
                    segments,
                    line,
                    inline: stack(),
                    in_use: true,
                });
            }
            i = end.max(i + 1);
            continue;
        } else if t.kind == Kind::Ident
            && next(1).is_some_and(|n| n.is("::"))
            && next(2).is_some_and(|n| n.kind == Kind::Ident)
            && !prev.is_some_and(|p| p.is("::") || p.is("."))
            && (matches!(t.text.as_str(), "crate" | "super" | "self")
                || (inline.is_empty() && children.contains(t.text.as_str())))
        {
            let mut segments = vec![t.text.clone()];
            let mut j = i + 1;
            while tokens.get(j).is_some_and(|n| n.is("::"))
                && tokens.get(j + 1).is_some_and(|n| n.kind == Kind::Ident)
            {
                segments.push(tokens[j + 1].text.clone());
                j += 2;
            }
            parsed.paths.push(RawPath {
                segments,
                line: t.line,
                inline: stack(),
                in_use: false,
            });
            i = j;
            continue;
        }
        i += 1;
    }
    parsed
}

// ----------------------------------------------------------------------------------------------
// The crate: files, modules and the paths between them.

/// A source file, its path relative to the repository root (`src/a/b.rs`).
struct Source {
    path: String,
    text: String,
}

#[derive(Debug, Clone, PartialEq)]
enum Status {
    /// Declared by its parent module: compiled into the library.
    Compiled,
    /// Declared under `#[cfg(test)]` (or inside such a module), or `#![cfg(test)]`.
    Test,
    /// Not compiled at all: `parent` has no `mod name;` for it (or for a folder above it).
    Orphan { parent: String, name: String },
}

/// A path that leads into the crate's modules.
#[derive(Debug, Clone)]
struct Edge {
    line: usize,
    /// As written, `use` trees expanded: `crate::sim::pick::PickReason`.
    written: String,
    /// The module path it names, from the crate root (re-exports of src/lib.rs followed).
    target: Vec<String>,
    /// The deepest file of that path.
    target_file: String,
}

struct FileInfo {
    path: String,
    /// `src/a/b.rs` and `src/a/b/mod.rs` are both `[a, b]`.
    module: Vec<String>,
    status: Status,
    edges: Vec<Edge>,
}

struct Analysis {
    table: Result<Vec<Layer>, String>,
    /// The top-level `mod` declarations of src/lib.rs.
    lib_mods: Vec<ModDecl>,
    /// Every file but src/lib.rs and src/main.rs, by path.
    files: Vec<FileInfo>,
}

/// The module path of a file under src/; `None` for src/lib.rs and the binaries' files
/// (src/main.rs, src/bin/), which are other crates.
fn module_of(path: &str) -> Option<Vec<String>> {
    let rel = path.strip_prefix("src/")?.strip_suffix(".rs")?;
    if rel == "lib" || rel == "main" || rel.starts_with("bin/") {
        return None;
    }
    let mut parts: Vec<String> = rel.split('/').map(str::to_owned).collect();
    if parts.len() > 1 && parts.last().is_some_and(|p| p == "mod") {
        parts.pop();
    }
    Some(parts)
}

fn analyse(sources: &[Source]) -> Analysis {
    let lib = sources.iter().find(|s| s.path == "src/lib.rs");
    let table = match lib {
        Some(lib) => parse_table(&lib.text),
        None => Err("src/lib.rs is missing".to_owned()),
    };
    let lib_parsed = lib.map(|l| parse_file(&l.text)).unwrap_or_default();

    let mut by_module: BTreeMap<Vec<String>, (&Source, Parsed)> = BTreeMap::new();
    for source in sources {
        if let Some(module) = module_of(&source.path) {
            by_module.insert(module, (source, parse_file(&source.text)));
        }
    }
    let file_of = |module: &[String]| -> Option<String> {
        if module.is_empty() {
            return Some("src/lib.rs".to_owned());
        }
        by_module.get(module).map(|(s, _)| s.path.clone())
    };
    let mods_of = |module: &[String]| -> Option<&Vec<ModDecl>> {
        if module.is_empty() {
            Some(&lib_parsed.mods)
        } else {
            by_module.get(module).map(|(_, p)| &p.mods)
        }
    };
    let status = |module: &[String]| -> Status {
        // The nearest reason, walking up: a test file, a test declaration, a missing one.
        for len in (1..=module.len()).rev() {
            let here = &module[..len];
            if by_module.get(here).is_some_and(|(_, p)| p.test_only) {
                return Status::Test;
            }
            let parent = &here[..len - 1];
            match mods_of(parent).and_then(|m| m.iter().find(|d| d.name == here[len - 1])) {
                Some(decl) if decl.test => return Status::Test,
                Some(_) => {}
                None => {
                    return Status::Orphan {
                        parent: file_of(parent).unwrap_or_else(|| parent.join("/")),
                        name: here[len - 1].clone(),
                    }
                }
            }
        }
        Status::Compiled
    };
    // What src/lib.rs imports can be named as `crate::Name`.
    let lib_children: BTreeSet<String> = lib_parsed
        .mods
        .iter()
        .filter(|m| !m.test)
        .map(|m| m.name.clone())
        .collect();
    let reexports: BTreeMap<String, Vec<String>> = lib_parsed
        .paths
        .iter()
        .filter(|p| p.in_use && p.inline.is_empty())
        .filter_map(|p| {
            let abs = resolve(p, &[], &lib_children)?;
            Some((abs.last()?.clone(), abs))
        })
        .collect();

    let mut files = Vec::new();
    for (module, (source, parsed)) in &by_module {
        let children: BTreeSet<String> = parsed
            .mods
            .iter()
            .filter(|m| !m.test)
            .map(|m| m.name.clone())
            .collect();
        let mut edges = Vec::new();
        for path in &parsed.paths {
            let Some(mut target) = resolve(path, module, &children) else {
                continue;
            };
            if !by_module.contains_key(&target[..1]) {
                match reexports.get(&target[0]) {
                    Some(full) => target = [&full[..], &target[1..]].concat(),
                    None => continue, // a macro or item of the crate root
                }
            }
            let Some(target_file) = (1..=target.len()).rev().find_map(|n| file_of(&target[..n]))
            else {
                continue;
            };
            edges.push(Edge {
                line: path.line,
                written: path.segments.join("::"),
                target,
                target_file,
            });
        }
        files.push(FileInfo {
            path: source.path.clone(),
            module: module.clone(),
            status: status(module),
            edges,
        });
    }
    Analysis {
        table,
        lib_mods: lib_parsed.mods,
        files,
    }
}

/// The module path a written path names, from the crate root; `None` outside the crate.
fn resolve(path: &RawPath, module: &[String], children: &BTreeSet<String>) -> Option<Vec<String>> {
    let here: Vec<String> = module.iter().chain(&path.inline).cloned().collect();
    let segments = &path.segments;
    let first = segments.first()?;
    let abs = match first.as_str() {
        "crate" => segments[1..].to_vec(),
        "self" => [&here[..], &segments[1..]].concat(),
        "super" => {
            let ups = segments.iter().take_while(|s| *s == "super").count();
            let base = here.len().checked_sub(ups)?;
            [&here[..base], &segments[ups..]].concat()
        }
        name if path.inline.is_empty() && children.contains(name) => {
            [&here[..], &segments[..]].concat()
        }
        _ => return None,
    };
    (!abs.is_empty()).then_some(abs)
}

// ----------------------------------------------------------------------------------------------
// The checks. Each returns its violations, one line each.

/// The layer a top-level module is in.
fn layer_of<'a>(layers: &'a [Layer], module: &str) -> Option<&'a Layer> {
    layers
        .iter()
        .find(|l| l.modules.iter().any(|m| m == module))
}

/// a) Every module of src/lib.rs in exactly one layer, every module of the table declared,
/// every layer a row may use listed above it, and no file left out of the crate.
fn check_table(a: &Analysis) -> Vec<String> {
    let layers = match &a.table {
        Ok(layers) => layers,
        Err(e) => return vec![e.clone()],
    };
    let mut out = Vec::new();
    for decl in a.lib_mods.iter().filter(|d| !d.test) {
        let homes: Vec<&str> = layers
            .iter()
            .filter(|l| l.modules.contains(&decl.name))
            .map(|l| l.name.as_str())
            .collect();
        match homes.len() {
            1 => {}
            0 => out.push(format!(
                "src/lib.rs:{}: module `{}` is in no layer of the table",
                decl.line, decl.name
            )),
            _ => out.push(format!(
                "src/lib.rs:{}: module `{}` is in {} layers: {}",
                decl.line,
                decl.name,
                homes.len(),
                homes.join(", ")
            )),
        }
    }
    for (i, layer) in layers.iter().enumerate() {
        if layers[..i].iter().any(|l| l.name == layer.name) {
            out.push(format!(
                "src/lib.rs:{}: layer `{}` has two rows",
                layer.line, layer.name
            ));
        }
        for module in &layer.modules {
            match a.lib_mods.iter().find(|d| &d.name == module) {
                Some(d) if !d.test => {}
                Some(_) => out.push(format!(
                    "src/lib.rs:{}: layer `{}` lists `{module}`, which src/lib.rs declares only \
                     under #[cfg(test)]",
                    layer.line, layer.name
                )),
                None => out.push(format!(
                    "src/lib.rs:{}: layer `{}` lists `{module}`, which src/lib.rs does not declare",
                    layer.line, layer.name
                )),
            }
        }
        for used in &layer.may_use {
            match layers.iter().position(|l| &l.name == used) {
                Some(j) if j < i => {}
                Some(_) => out.push(format!(
                    "src/lib.rs:{}: layer `{}` may use `{used}`, which is not above it: imports \
                     run downwards",
                    layer.line, layer.name
                )),
                None => out.push(format!(
                    "src/lib.rs:{}: layer `{}` may use `{used}`, which is no layer",
                    layer.line, layer.name
                )),
            }
        }
    }
    for file in &a.files {
        if let Status::Orphan { parent, name } = &file.status {
            out.push(format!(
                "{}: not compiled: {parent} has no `mod {name};`",
                file.path
            ));
        }
    }
    out
}

/// The files whose code counts: compiled or left out, never test code.
fn checked_files(a: &Analysis) -> impl Iterator<Item = &FileInfo> {
    a.files.iter().filter(|f| f.status != Status::Test)
}

/// b) Every path from one top-level module into another goes to its own layer or one its row
/// may use.
fn check_layers(a: &Analysis) -> Vec<String> {
    let Ok(layers) = &a.table else {
        return vec!["no layer table (see the table check)".to_owned()];
    };
    let mut out = Vec::new();
    for file in checked_files(a) {
        let from = &file.module[0];
        for edge in &file.edges {
            let to = &edge.target[0];
            if to == from {
                continue;
            }
            // A module in no layer is the table check's to report.
            let (Some(lf), Some(lt)) = (layer_of(layers, from), layer_of(layers, to)) else {
                continue;
            };
            if lf.name != lt.name && !lf.may_use.contains(&lt.name) {
                out.push(format!(
                    "{}:{}: `{}`: {from} (layer {}) → {to} (layer {}); layer {} may use: {}",
                    file.path,
                    edge.line,
                    edge.written,
                    lf.name,
                    lt.name,
                    lf.name,
                    if lf.may_use.is_empty() {
                        "only its own modules".to_owned()
                    } else {
                        lf.may_use.join(", ")
                    }
                ));
            }
        }
    }
    out
}

/// d) No module below `commands` imports `crate::commands`.
fn check_commands(a: &Analysis) -> Vec<String> {
    let Ok(layers) = &a.table else {
        return vec!["no layer table (see the table check)".to_owned()];
    };
    let Some(commands) = layer_of(layers, "commands") else {
        return vec!["the layer table has no `commands` module".to_owned()];
    };
    let mut out = Vec::new();
    for file in checked_files(a) {
        let from = &file.module[0];
        if from == "commands" {
            continue;
        }
        let layer = layer_of(layers, from);
        if layer.is_some_and(|l| l.name == commands.name || l.may_use.contains(&commands.name)) {
            continue;
        }
        for edge in file.edges.iter().filter(|e| e.target[0] == "commands") {
            out.push(format!(
                "{}:{}: `{}`: {from} ({}) imports from crate::commands, which sits above it",
                file.path,
                edge.line,
                edge.written,
                layer.map_or("in no layer".to_owned(), |l| format!("layer {}", l.name)),
            ));
        }
    }
    out
}

/// c) No cycle of file-to-file imports. Each group of files that reach each other is reported
/// with the shortest cycle through each of its files, every step with the line that makes it.
fn check_cycles(a: &Analysis) -> Vec<String> {
    let files: Vec<&FileInfo> = checked_files(a).collect();
    let index: BTreeMap<&str, usize> = files
        .iter()
        .enumerate()
        .map(|(i, f)| (f.path.as_str(), i))
        .collect();
    // The first path that makes each edge.
    let mut graph: Vec<BTreeMap<usize, &Edge>> = vec![BTreeMap::new(); files.len()];
    for (i, file) in files.iter().enumerate() {
        for edge in &file.edges {
            if let Some(&j) = index.get(edge.target_file.as_str()) {
                if j != i {
                    graph[i].entry(j).or_insert(edge);
                }
            }
        }
    }
    let mut out = Vec::new();
    for group in strongly_connected(&graph)
        .into_iter()
        .filter(|g| g.len() > 1)
    {
        let members: BTreeSet<usize> = group.iter().copied().collect();
        let mut cycles = BTreeSet::new();
        for &start in &members {
            if let Some(mut cycle) = shortest_cycle(&graph, &members, start) {
                let min = (0..cycle.len()).min_by_key(|&k| cycle[k]).unwrap();
                cycle.rotate_left(min);
                cycles.insert(cycle);
            }
        }
        let names: Vec<&str> = members.iter().map(|&m| files[m].path.as_str()).collect();
        for cycle in cycles {
            let steps: Vec<String> = (0..cycle.len())
                .map(|k| {
                    let (from, to) = (cycle[k], cycle[(k + 1) % cycle.len()]);
                    let edge = graph[from][&to];
                    format!("{}:{} `{}`", files[from].path, edge.line, edge.written)
                })
                .collect();
            let mut line = format!(
                "import cycle: {} → {}",
                steps.join(" → "),
                files[cycle[0]].path
            );
            if members.len() > cycle.len() {
                line.push_str(&format!(" (one of the cycles among {})", names.join(", ")));
            }
            out.push(line);
        }
    }
    out
}

/// Tarjan's strongly connected components.
fn strongly_connected(graph: &[BTreeMap<usize, &Edge>]) -> Vec<Vec<usize>> {
    struct State {
        index: Vec<Option<usize>>,
        low: Vec<usize>,
        on_stack: Vec<bool>,
        stack: Vec<usize>,
        next: usize,
        groups: Vec<Vec<usize>>,
    }
    fn visit(v: usize, graph: &[BTreeMap<usize, &Edge>], s: &mut State) {
        s.index[v] = Some(s.next);
        s.low[v] = s.next;
        s.next += 1;
        s.stack.push(v);
        s.on_stack[v] = true;
        for &w in graph[v].keys() {
            match s.index[w] {
                None => {
                    visit(w, graph, s);
                    s.low[v] = s.low[v].min(s.low[w]);
                }
                Some(iw) if s.on_stack[w] => s.low[v] = s.low[v].min(iw),
                Some(_) => {}
            }
        }
        if Some(s.low[v]) == s.index[v] {
            let mut group = Vec::new();
            while let Some(w) = s.stack.pop() {
                s.on_stack[w] = false;
                group.push(w);
                if w == v {
                    break;
                }
            }
            group.sort();
            s.groups.push(group);
        }
    }
    let n = graph.len();
    let mut s = State {
        index: vec![None; n],
        low: vec![0; n],
        on_stack: vec![false; n],
        stack: Vec::new(),
        next: 0,
        groups: Vec::new(),
    };
    for v in 0..n {
        if s.index[v].is_none() {
            visit(v, graph, &mut s);
        }
    }
    s.groups.sort();
    s.groups
}

/// The shortest cycle through `start` within `members`, as its nodes from `start` on.
fn shortest_cycle(
    graph: &[BTreeMap<usize, &Edge>],
    members: &BTreeSet<usize>,
    start: usize,
) -> Option<Vec<usize>> {
    let mut came_from: BTreeMap<usize, usize> = BTreeMap::new();
    let mut queue = VecDeque::from([start]);
    while let Some(v) = queue.pop_front() {
        for &w in graph[v].keys().filter(|w| members.contains(w)) {
            if w == start {
                let mut cycle = vec![v];
                while let Some(&p) = came_from.get(cycle.last().unwrap()) {
                    cycle.push(p);
                }
                cycle.reverse();
                return Some(cycle);
            }
            if w != start && !came_from.contains_key(&w) {
                came_from.insert(w, v);
                queue.push_back(w);
            }
        }
    }
    None
}

// ----------------------------------------------------------------------------------------------
// The checks on the repository's src/.

fn read_tree(dir: &Path, root: &Path, out: &mut Vec<Source>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("reading {}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            read_tree(&path, root, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            let rel = path.strip_prefix(root).unwrap();
            let rel: Vec<String> = rel
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect();
            out.push(Source {
                path: rel.join("/"),
                text: std::fs::read_to_string(&path)
                    .unwrap_or_else(|e| panic!("reading {}: {e}", path.display())),
            });
        }
    }
}

fn repository() -> Analysis {
    let root = Path::new(option_env!("CARGO_MANIFEST_DIR").unwrap_or("."));
    let mut sources = Vec::new();
    read_tree(&root.join("src"), root, &mut sources);
    assert!(
        sources.iter().any(|s| s.path == "src/lib.rs"),
        "no src/lib.rs under {}",
        root.display()
    );
    analyse(&sources)
}

fn assert_none(violations: Vec<String>, what: &str) {
    assert!(
        violations.is_empty(),
        "{what} ({} violations; the table is in src/lib.rs):\n{}",
        violations.len(),
        violations.join("\n")
    );
}

#[test]
fn every_module_is_in_exactly_one_layer_of_the_table() {
    assert_none(
        check_table(&repository()),
        "src/lib.rs's modules and its layer table disagree",
    );
}

#[test]
fn imports_stay_in_their_layer_or_go_to_one_it_may_use() {
    assert_none(
        check_layers(&repository()),
        "imports that the layer table does not allow",
    );
}

#[test]
fn nothing_below_commands_imports_commands() {
    assert_none(
        check_commands(&repository()),
        "modules below `commands` that import from crate::commands",
    );
}

#[test]
fn no_files_import_each_other_in_a_cycle() {
    assert_none(
        check_cycles(&repository()),
        "file-level import cycles in src/",
    );
}

// ----------------------------------------------------------------------------------------------
// Function length.

/// The most lines a function in src/ may span (issue 44), tests included.
const MAX_FN_LINES: usize = 80;

/// Functions over [`MAX_FN_LINES`] not yet split, each with the length it may not exceed:
/// (file, name, lines). An entry that has grown fails the test, and so does one that is no
/// longer over the limit (remove it then), so the list only shrinks.
const NOT_YET_SPLIT: &[(&str, &str, usize)] = &[];

/// Every function with a body in `src`: its name, the line of its `fn` and the number of lines
/// from that line to the line of the `}` that closes its body, both counted (doc comments and
/// attributes above the `fn` line are not). Measured on the tokens of `lex`, so braces in
/// comments, strings and characters are not counted: after `fn name`, the first `{` or `;`
/// outside parentheses, brackets and angle brackets opens the body (a `;` first: a declaration
/// without one, skipped), and its `}` is found by brace matching. A function inside another is
/// measured on its own and counts towards the outer one too. `fn(…)` pointer types, which have
/// no name, are not functions.
fn function_lengths(src: &str) -> Vec<(String, usize, usize)> {
    let tokens = lex(src);
    let mut found = Vec::new();
    for (i, token) in tokens.iter().enumerate() {
        let Some(name) = tokens.get(i + 1) else { break };
        if !token.is("fn") || name.kind != Kind::Ident {
            continue;
        }
        let mut depth = 0i32;
        let mut open = None;
        for (j, t) in tokens.iter().enumerate().skip(i + 2) {
            match t.text.as_str() {
                _ if t.kind == Kind::Literal => {}
                "(" | "[" | "<" => depth += 1,
                // `->` is no closing angle bracket.
                ">" if tokens[j - 1].is("-") => {}
                ")" | "]" | ">" => depth -= 1,
                "{" if depth <= 0 => {
                    open = Some(j);
                    break;
                }
                ";" if depth <= 0 => break,
                _ => {}
            }
        }
        let Some(open) = open else { continue };
        let mut braces = 0;
        for t in &tokens[open..] {
            if t.is("{") {
                braces += 1;
            } else if t.is("}") {
                braces -= 1;
                if braces == 0 {
                    found.push((name.text.clone(), token.line, t.line - token.line + 1));
                    break;
                }
            }
        }
    }
    found
}

/// Every function in src/ longer than `max` lines, longest first, as `path:line: fn name: n lines`,
/// but those of `allowed` (file, name, lines) within their own length; and every entry of
/// `allowed` that is no longer over `max`.
fn long_functions(sources: &[Source], max: usize, allowed: &[(&str, &str, usize)]) -> Vec<String> {
    let mut long: Vec<(usize, String)> = Vec::new();
    let mut still_long = BTreeSet::new();
    for s in sources {
        for (name, line, n) in function_lengths(&s.text) {
            if n <= max {
                continue;
            }
            let known = allowed.iter().find(|(p, f, _)| *p == s.path && *f == name);
            if let Some(&(_, _, most)) = known {
                still_long.insert((s.path.as_str(), name.clone()));
                if n <= most {
                    continue;
                }
            }
            long.push((n, format!("{}:{line}: fn {name}: {n} lines", s.path)));
        }
    }
    long.sort_by(|a, b| b.0.cmp(&a.0).then_with(|| a.1.cmp(&b.1)));
    let mut found: Vec<String> = long.into_iter().map(|(_, l)| l).collect();
    for (path, name, _) in allowed {
        if !still_long.contains(&(*path, name.to_string())) {
            found.push(format!(
                "{path}: fn {name} is no longer over {max} lines: remove it from NOT_YET_SPLIT"
            ));
        }
    }
    found
}

#[test]
fn no_function_in_src_is_longer_than_80_lines() {
    let root = Path::new(option_env!("CARGO_MANIFEST_DIR").unwrap_or("."));
    let mut sources = Vec::new();
    read_tree(&root.join("src"), root, &mut sources);
    let long = long_functions(&sources, MAX_FN_LINES, NOT_YET_SPLIT);
    assert!(
        long.is_empty(),
        "functions in src/ longer than {MAX_FN_LINES} lines (split them):\n{}",
        long.join("\n")
    );
}

// ----------------------------------------------------------------------------------------------
// The parser and the graph on small inputs.

#[cfg(test)]
mod logic {
    use super::*;

    const LIB: &str = "\
//! Layers.
//!
//! | layer | modules | may use |
//! |---|---|---|
//! | core | [`base`], geo | |
//! | mid | mid | core |
//! | commands | commands | core, mid |
//! | cli | cli | core, mid, commands |
//!
//! Prose after the table.

pub mod base;
pub mod geo;
pub mod mid;
pub(crate) mod commands;
pub mod cli;
#[cfg(test)]
mod fuzz;

pub use commands::stop::Stopped;
";

    fn crate_of(files: &[(&str, &str)]) -> Analysis {
        let mut sources: Vec<Source> = files
            .iter()
            .map(|(path, text)| Source {
                path: path.to_string(),
                text: text.to_string(),
            })
            .collect();
        if !files.iter().any(|(p, _)| *p == "src/lib.rs") {
            sources.push(Source {
                path: "src/lib.rs".to_owned(),
                text: LIB.to_owned(),
            });
        }
        analyse(&sources)
    }

    /// The well-layered crate every case starts from.
    fn base_files() -> Vec<(&'static str, &'static str)> {
        vec![
            ("src/base.rs", "pub struct B;\n"),
            ("src/geo/mod.rs", "mod shape;\npub use shape::Shape;\n"),
            ("src/geo/shape.rs", "pub struct Shape;\n"),
            (
                "src/mid.rs",
                "use crate::base::B;\nuse crate::geo::Shape;\n",
            ),
            ("src/commands/mod.rs", "pub mod stop;\nuse crate::mid;\n"),
            ("src/commands/stop.rs", "pub struct Stopped;\n"),
            ("src/cli.rs", "use crate::commands::stop::Stopped;\n"),
            (
                "src/fuzz.rs",
                "use crate::cli::x;\nuse crate::commands::y;\n",
            ),
            ("src/main.rs", "use crate::nothing;\nfn main() {}\n"),
            ("src/bin/tool.rs", "use crate::nothing;\nfn main() {}\n"),
        ]
    }

    fn with(extra: &[(&'static str, &'static str)]) -> Analysis {
        let mut files = base_files();
        for (path, text) in extra {
            files.retain(|(p, _)| p != path);
            files.push((path, text));
        }
        crate_of(&files)
    }

    fn paths(src: &str) -> Vec<(String, usize)> {
        parse_file(src)
            .paths
            .into_iter()
            .map(|p| (p.segments.join("::"), p.line))
            .collect()
    }

    #[test]
    fn the_table_is_read_from_the_doc() {
        let layers = parse_table(LIB).unwrap();
        let names: Vec<&str> = layers.iter().map(|l| l.name.as_str()).collect();
        assert_eq!(names, ["core", "mid", "commands", "cli"]);
        assert_eq!(layers[0].modules, ["base", "geo"]);
        assert!(layers[0].may_use.is_empty());
        assert_eq!(layers[3].may_use, ["core", "mid", "commands"]);
        assert_eq!(layers[0].line, 5);
        assert!(parse_table("//! no table here\npub mod a;\n").is_err());
        assert!(parse_table("//! | layer | modules | may use |\n//! |---|---|---|\n").is_err());
        assert!(parse_table("//! | layer | modules | may use |\n//! | a | b |\n").is_err());
    }

    #[test]
    fn comments_strings_and_characters_hide_no_paths_and_no_braces() {
        let src = r####"
// use crate::a::B;
/// crate::doc::C
//! crate::inner::D
/* crate::block::E /* nested crate::x::y */ still a comment crate::z::w */
fn f<'a>(x: &'a str) -> char {
    let s = "crate::in_string::F {";
    let r = r#"crate::raw::G "{ "#;
    let b = b"crate::bytes::H";
    let c = '{';
    let q = '\'';
    let u = '\u{7b}';
    let bc = b'{';
    'outer: loop { break 'outer; }
    crate::real::Path::new()
}
use crate::after::All;
"####;
        assert_eq!(
            paths(src),
            [
                ("crate::real::Path::new".to_owned(), 15),
                ("crate::after::All".to_owned(), 17)
            ]
        );
    }

    #[test]
    fn use_trees_expand_over_lines_with_the_line_of_each_leaf() {
        let src = "use crate::{\n    a::{self, b::C},\n    d as e,\n    f::*,\n};\n\
                   pub(crate) use super::g::{H, I};\nuse std::io;\nuse ::ext::Thing;\n";
        assert_eq!(
            paths(src),
            [
                ("crate::a".to_owned(), 2),
                ("crate::a::b::C".to_owned(), 2),
                ("crate::d".to_owned(), 3),
                ("crate::f".to_owned(), 4),
                ("super::g::H".to_owned(), 6),
                ("super::g::I".to_owned(), 6),
                ("std::io".to_owned(), 7),
                ("::::ext::Thing".to_owned(), 8),
            ]
        );
    }

    #[test]
    fn paths_in_code_are_found_but_not_fields_methods_or_other_crates() {
        let src = "mod child;\nfn f() {\n    let x = super::super::a::b(self::c::D);\n    \
                   child::go();\n    x.child::<u8>();\n    other::child::go();\n    \
                   std::mem::drop(crate::k::L::<u8>::new());\n}\n";
        assert_eq!(
            paths(src),
            [
                ("super::super::a::b".to_owned(), 3),
                ("self::c::D".to_owned(), 3),
                ("child::go".to_owned(), 4),
                ("crate::k::L".to_owned(), 7),
            ]
        );
    }

    #[test]
    fn test_code_is_skipped_wherever_it_sits() {
        let src = "\
#[cfg(test)]
use crate::early::Test;
#[cfg(test)]
pub(crate) const NAMES: [&str; 2] = [\"a\", \"b\"];
struct S {
    #[cfg(test)]
    probe: crate::field::Probe,
    kept: crate::field::Kept,
}
impl S {
    #[cfg(test)]
    #[allow(dead_code)]
    pub(crate) fn only_in_tests(&self) -> crate::method::M { crate::method::M }
    fn real(&self) { crate::middle::Real::go() }
}
#[cfg(all(test, feature = \"slow\"))]
fn slow() { crate::slow::S }
#[cfg(test)]
mod tests {
    use crate::late::T;
    fn t() { crate::late::U }
}
#[cfg(test)]
mod fuzz;
fn tail() { crate::tail::V }
";
        let parsed = parse_file(src);
        let found: Vec<String> = parsed.paths.iter().map(|p| p.segments.join("::")).collect();
        assert_eq!(
            found,
            [
                "crate::field::Kept",
                "crate::middle::Real::go",
                "crate::tail::V"
            ]
        );
        assert_eq!(
            parsed.mods,
            [ModDecl {
                name: "fuzz".to_owned(),
                test: true,
                line: 24
            }]
        );
        assert!(parse_file("#![cfg(test)]\nuse crate::a::B;\n").test_only);
    }

    #[test]
    fn paths_resolve_to_the_deepest_file() {
        let a = with(&[
            (
                "src/mid.rs",
                "fn f() { crate::geo::shape::Shape::new(); crate::geo::Shape; }\n",
            ),
            ("src/cli.rs", "use crate::Stopped;\n"),
        ]);
        let file = |p: &str| a.files.iter().find(|f| f.path == p).unwrap();
        let targets: Vec<&str> = file("src/mid.rs")
            .edges
            .iter()
            .map(|e| e.target_file.as_str())
            .collect();
        assert_eq!(targets, ["src/geo/shape.rs", "src/geo/mod.rs"]);
        // A re-export of src/lib.rs leads to where it comes from.
        let edge = &file("src/cli.rs").edges[0];
        assert_eq!(edge.target, ["commands", "stop", "Stopped"]);
        assert_eq!(edge.target_file, "src/commands/stop.rs");
        // `super::` from a mod.rs is its folder's parent; from a file, its folder's module.
        let b = with(&[
            (
                "src/geo/mod.rs",
                "mod shape;\nmod inner;\nuse super::base::B;\n",
            ),
            ("src/geo/inner/mod.rs", "use super::shape::Shape;\n"),
        ]);
        let inner = b
            .files
            .iter()
            .find(|f| f.path == "src/geo/inner/mod.rs")
            .unwrap();
        assert_eq!(inner.edges[0].target_file, "src/geo/shape.rs");
        let geo = b.files.iter().find(|f| f.path == "src/geo/mod.rs").unwrap();
        assert_eq!(geo.edges[0].target_file, "src/base.rs");
    }

    #[test]
    fn a_well_layered_crate_passes_every_check() {
        let a = with(&[]);
        assert_eq!(check_table(&a), Vec::<String>::new());
        assert_eq!(check_layers(&a), Vec::<String>::new());
        assert_eq!(check_commands(&a), Vec::<String>::new());
        assert_eq!(check_cycles(&a), Vec::<String>::new());
        // Test-only files import what they like.
        let fuzz = a.files.iter().find(|f| f.path == "src/fuzz.rs").unwrap();
        assert_eq!(fuzz.status, Status::Test);
    }

    #[test]
    fn a_forbidden_edge_is_named_with_its_file_and_line() {
        let a = with(&[(
            "src/base.rs",
            "pub struct B;\n\nuse crate::{\n    geo::Shape,\n    mid::M,\n};\n",
        )]);
        assert_eq!(
            check_layers(&a),
            [
                "src/base.rs:5: `crate::mid::M`: base (layer core) → mid (layer mid); layer core \
              may use: only its own modules"
            ]
        );
    }

    #[test]
    fn importing_commands_from_below_has_its_own_message() {
        let a = with(&[(
            "src/mid.rs",
            "fn f() -> crate::commands::stop::Stopped { todo!() }\n",
        )]);
        let found = check_commands(&a);
        assert_eq!(
            found,
            [
                "src/mid.rs:1: `crate::commands::stop::Stopped`: mid (layer mid) imports from \
              crate::commands, which sits above it"
            ]
        );
        assert_eq!(check_layers(&a).len(), 1);
        // Through src/lib.rs's re-export as well.
        let b = with(&[("src/base.rs", "use crate::Stopped;\n")]);
        assert_eq!(check_commands(&b).len(), 1, "{:?}", check_commands(&b));
    }

    #[test]
    fn a_two_file_cycle_is_found() {
        let a = with(&[
            ("src/geo/mod.rs", "mod shape;\nmod area;\n"),
            (
                "src/geo/shape.rs",
                "use super::area::Area;\npub struct Shape;\n",
            ),
            (
                "src/geo/area.rs",
                "pub struct Area;\nfn f() { crate::geo::shape::Shape; }\n",
            ),
            ("src/mid.rs", "use crate::base::B;\n"),
        ]);
        assert_eq!(
            check_cycles(&a),
            [
                "import cycle: src/geo/area.rs:2 `crate::geo::shape::Shape` → src/geo/shape.rs:1 \
              `super::area::Area` → src/geo/area.rs"
            ]
        );
        // Same layer, so no layer violation.
        assert_eq!(check_layers(&a), Vec::<String>::new());
    }

    #[test]
    fn a_child_that_uses_its_parent_is_a_cycle_only_if_the_parent_uses_it() {
        // src/geo/mod.rs re-exports shape; shape reaching up with `super::` closes the loop.
        let a = with(&[("src/geo/shape.rs", "use super::Unit;\npub struct Shape;\n")]);
        assert_eq!(
            check_cycles(&a),
            ["import cycle: src/geo/mod.rs:2 `shape::Shape` → src/geo/shape.rs:1 `super::Unit` → \
              src/geo/mod.rs"]
        );
        // Only declaring the child is no edge.
        let b = with(&[
            ("src/geo/mod.rs", "mod shape;\npub struct Unit;\n"),
            ("src/geo/shape.rs", "use super::Unit;\npub struct Shape;\n"),
            ("src/mid.rs", "use crate::base::B;\n"),
        ]);
        assert_eq!(check_cycles(&b), Vec::<String>::new());
    }

    #[test]
    fn a_longer_cycle_is_reported_once_with_its_group() {
        let a = with(&[
            ("src/geo/mod.rs", "mod a;\nmod b;\nmod c;\n"),
            ("src/geo/a.rs", "use super::b::X;\n"),
            ("src/geo/b.rs", "use super::c::X;\n"),
            ("src/geo/c.rs", "use super::a::X;\nuse super::b::Y;\n"),
            ("src/mid.rs", ""),
        ]);
        let found = check_cycles(&a);
        assert_eq!(found.len(), 2, "{found:#?}");
        assert!(
            found[0].starts_with("import cycle: src/geo/a.rs:1"),
            "{found:#?}"
        );
        assert!(
            found[1].starts_with("import cycle: src/geo/b.rs:1"),
            "{found:#?}"
        );
        // a → b → c → a and b → c → b: the first is the whole group, the second a part of it.
        assert!(!found[0].contains("one of the cycles among"), "{found:#?}");
        assert!(found[1].contains("one of the cycles among"), "{found:#?}");
    }

    #[test]
    fn inline_modules_resolve_super_to_their_own_file() {
        let a = with(&[(
            "src/mid.rs",
            "pub(crate) mod groups {\n    use super::Thing;\n    pub const G: u8 = 1;\n}\n\
             pub struct Thing;\nfn f() { groups::G; }\n",
        )]);
        let mid = a.files.iter().find(|f| f.path == "src/mid.rs").unwrap();
        assert!(mid.edges.iter().all(|e| e.target_file == "src/mid.rs"));
        assert_eq!(check_cycles(&a), Vec::<String>::new());
    }

    #[test]
    fn function_lengths_match_braces_from_the_fn_line() {
        let src = "\
/// Docs and attributes are not counted.
#[inline]
pub(crate) fn short<T: Into<u8>>(x: T) -> u8 {
    x.into()
}
trait T {
    fn declared(&self) -> Vec<u8>;
    fn provided(&self)
    where
        Self: Sized,
    {
        let f: fn(u8) -> u8 = |x| x; // { not a brace
        let s = \"}}}\";
        let c = '{';
        /* } */
        inner();
        fn inner() {}
    }
}
";
        assert_eq!(
            function_lengths(src),
            [
                ("short".to_owned(), 3, 3),
                ("provided".to_owned(), 8, 11),
                ("inner".to_owned(), 17, 1),
            ]
        );
        let sources = [Source {
            path: "src/a.rs".to_owned(),
            text: src.to_owned(),
        }];
        assert_eq!(
            long_functions(&sources, 3, &[]),
            ["src/a.rs:8: fn provided: 11 lines"]
        );
        assert_eq!(long_functions(&sources, 11, &[]), Vec::<String>::new());
        // A function not yet split passes within its recorded length, fails beyond it, and its
        // entry fails once it is split.
        assert!(long_functions(&sources, 3, &[("src/a.rs", "provided", 11)]).is_empty());
        assert_eq!(
            long_functions(&sources, 3, &[("src/a.rs", "provided", 10)]),
            ["src/a.rs:8: fn provided: 11 lines"]
        );
        assert_eq!(
            long_functions(&sources, 11, &[("src/a.rs", "provided", 11)]),
            ["src/a.rs: fn provided is no longer over 11 lines: remove it from NOT_YET_SPLIT"]
        );
    }

    #[test]
    fn table_and_declarations_must_agree() {
        let lib = LIB
            .replace("pub mod geo;\n", "")
            .replace("#[cfg(test)]\nmod fuzz;\n", "pub mod fuzz;\n")
            .replace(
                "| cli | cli | core, mid, commands |",
                "| cli | cli | core, mid, commands, cli |",
            )
            .replace("| mid | mid | core |", "| mid | mid | core, nowhere |");
        let mut files = base_files();
        files.push(("src/lib.rs", Box::leak(lib.into_boxed_str())));
        files.push(("src/stray/mod.rs", "use crate::base::B;\n"));
        let found = check_table(&crate_of(&files));
        let expected = [
            "src/lib.rs:16: module `fuzz` is in no layer of the table",
            "src/lib.rs:5: layer `core` lists `geo`, which src/lib.rs does not declare",
            "src/lib.rs:6: layer `mid` may use `nowhere`, which is no layer",
            "src/lib.rs:8: layer `cli` may use `cli`, which is not above it: imports run \
             downwards",
            "src/geo/mod.rs: not compiled: src/lib.rs has no `mod geo;`",
            "src/geo/shape.rs: not compiled: src/lib.rs has no `mod geo;`",
            "src/stray/mod.rs: not compiled: src/lib.rs has no `mod stray;`",
        ];
        assert_eq!(found, expected);
    }
}
