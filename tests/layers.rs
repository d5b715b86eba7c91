//! The layering of DESIGN.md "Layers", checked on the source: each rule reads the
//! library's files under src/ and fails listing every violation it found.
//!
//! Only code counts: comments (doc links included) and literals are skipped. A module
//! reference is a path starting with `crate::X` (grouped `crate::{a, b::c}` names each
//! of `a` and `b`), a `super::` chain that climbs to the crate root, or a name that
//! src/lib.rs re-exports (`crate::Renderer` is `render`).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// A token of Rust source: identifiers (keywords too) and punctuation; `::` is one token.
#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Ident(String),
    Punct(&'static str),
    Other(char),
}

/// Tokens with their line numbers; comments, strings, chars and lifetimes are dropped.
fn tokenize(src: &str) -> Vec<(Tok, usize)> {
    let c: Vec<char> = src.chars().collect();
    let (mut i, mut line, mut out) = (0, 1, Vec::new());
    let at = |i: usize| c.get(i).copied().unwrap_or('\0');
    while i < c.len() {
        let ch = c[i];
        if ch == '\n' {
            line += 1;
            i += 1;
        } else if ch.is_whitespace() {
            i += 1;
        } else if ch == '/' && at(i + 1) == '/' {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if ch == '/' && at(i + 1) == '*' {
            let mut depth = 0;
            loop {
                if i >= c.len() {
                    break;
                } else if c[i] == '/' && at(i + 1) == '*' {
                    depth += 1;
                    i += 2;
                } else if c[i] == '*' && at(i + 1) == '/' {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    line += usize::from(c[i] == '\n');
                    i += 1;
                }
            }
        } else if (ch == 'r' || ch == 'b')
            && (at(i + 1) == '"' || at(i + 1) == '#' || (at(i + 1) == 'r' && ch == 'b'))
            && raw_string_start(&c, i).is_some()
        {
            // Raw strings: r"..", r#".."#, br"..".
            let (hashes, body) = raw_string_start(&c, i).unwrap();
            i = body;
            let closing: Vec<char> = std::iter::once('"')
                .chain(std::iter::repeat_n('#', hashes))
                .collect();
            while i < c.len() && !c[i..].starts_with(&closing) {
                line += usize::from(c[i] == '\n');
                i += 1;
            }
            i += closing.len();
        } else if ch == '"' {
            i += 1;
            while i < c.len() && c[i] != '"' {
                if c[i] == '\\' {
                    i += 1;
                }
                line += usize::from(at(i) == '\n');
                i += 1;
            }
            i += 1;
        } else if ch == '\'' {
            // A char literal ('x', '\n', '\u{..}') or a lifetime ('a): both are skipped.
            if at(i + 1) == '\\' {
                i += 2;
                while i < c.len() && c[i] != '\'' {
                    i += 1;
                }
                i += 1;
            } else if at(i + 2) == '\'' {
                i += 3;
            } else {
                i += 1;
                while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
                    i += 1;
                }
            }
        } else if ch.is_alphabetic() || ch == '_' {
            let start = i;
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
                i += 1;
            }
            out.push((Tok::Ident(c[start..i].iter().collect()), line));
        } else if ch.is_ascii_digit() {
            while i < c.len()
                && (c[i].is_alphanumeric()
                    || c[i] == '_'
                    || (c[i] == '.' && at(i + 1).is_ascii_digit()))
            {
                i += 1;
            }
        } else if ch == ':' && at(i + 1) == ':' {
            out.push((Tok::Punct("::"), line));
            i += 2;
        } else {
            out.push((Tok::Other(ch), line));
            i += 1;
        }
    }
    out
}

/// If a raw string starts at `i`: its number of `#` and the index of its first character.
fn raw_string_start(c: &[char], i: usize) -> Option<(usize, usize)> {
    let mut j = i + 1;
    if c[i] == 'b' {
        if c.get(j) != Some(&'r') {
            return None;
        }
        j += 1;
    }
    let hashes = c[j..].iter().take_while(|&&h| h == '#').count();
    (c.get(j + hashes) == Some(&'"')).then_some((hashes, j + hashes + 1))
}

/// One library source file.
struct Source {
    /// Path relative to the crate root, e.g. `src/trace/wavefront.rs`.
    path: String,
    /// Its top-level module (`trace`); empty for src/lib.rs.
    top: String,
    /// Its module path below the crate root (`["trace", "wavefront"]`).
    module: Vec<String>,
    tokens: Vec<(Tok, usize)>,
}

/// Every library file: src/ without src/main.rs and src/bin/.
fn library() -> Vec<Source> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    collect(&root.join("src"), &mut files);
    files.sort();
    files
        .into_iter()
        .filter_map(|file| {
            let rel = file
                .strip_prefix(root)
                .unwrap()
                .to_string_lossy()
                .replace('\\', "/");
            let inner = rel.strip_prefix("src/").unwrap();
            if inner == "main.rs" || inner.starts_with("bin/") {
                return None;
            }
            let mut module: Vec<String> = inner
                .trim_end_matches(".rs")
                .split('/')
                .map(str::to_owned)
                .collect();
            if matches!(module.last().map(String::as_str), Some("mod" | "lib")) {
                module.pop();
            }
            let text = std::fs::read_to_string(&file).unwrap();
            Some(Source {
                path: rel,
                top: module.first().cloned().unwrap_or_default(),
                module,
                tokens: tokenize(&text),
            })
        })
        .collect()
}

fn collect(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            collect(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The top-level modules of the library, and what src/lib.rs re-exports from each.
fn top_level(files: &[Source]) -> (BTreeSet<String>, BTreeMap<String, String>) {
    let modules: BTreeSet<String> = files
        .iter()
        .map(|f| f.top.clone())
        .filter(|t| !t.is_empty())
        .collect();
    let mut reexports = BTreeMap::new();
    if let Some(lib) = files.iter().find(|f| f.path == "src/lib.rs") {
        let t = &lib.tokens;
        for i in 0..t.len().saturating_sub(2) {
            let (Tok::Ident(a), Tok::Ident(b)) = (&t[i].0, &t[i + 1].0) else {
                continue;
            };
            let Tok::Ident(m) = &t[i + 2].0 else {
                continue;
            };
            if a != "pub" || b != "use" || !modules.contains(m) {
                continue;
            }
            for (tok, _) in t[i + 3..]
                .iter()
                .take_while(|(tok, _)| *tok != Tok::Other(';'))
            {
                if let Tok::Ident(name) = tok {
                    reexports.entry(name.clone()).or_insert_with(|| m.clone());
                }
            }
        }
    }
    (modules, reexports)
}

/// A reference from one file to a top-level module.
#[derive(Clone, Debug)]
struct Reference {
    /// Referenced top-level module.
    to: String,
    /// `src/...rs:line`.
    at: String,
}

/// Every top-level module each file refers to, with where.
fn references(
    file: &Source,
    modules: &BTreeSet<String>,
    reexports: &BTreeMap<String, String>,
) -> Vec<Reference> {
    let t = &file.tokens;
    let ident = |k: usize| match t.get(k) {
        Some((Tok::Ident(s), _)) => Some(s.as_str()),
        _ => None,
    };
    let is = |k: usize, p: Tok| t.get(k).is_some_and(|(tok, _)| *tok == p);
    let resolve = |name: &str| {
        if modules.contains(name) {
            Some(name.to_owned())
        } else {
            reexports.get(name).cloned()
        }
    };
    // Names at the root of a path whose prefix ends before token `k`: one name, or
    // the first name of each item of a `{...}` group.
    let heads = |k: usize| -> Vec<(String, usize)> {
        if let Some(name) = ident(k) {
            return vec![(name.to_owned(), t[k].1)];
        }
        if !is(k, Tok::Other('{')) {
            return Vec::new();
        }
        let (mut out, mut depth, mut item_start) = (Vec::new(), 0, true);
        for (tok, line) in &t[k..] {
            match tok {
                Tok::Other('{') => {
                    depth += 1;
                    if depth == 1 {
                        item_start = true;
                    }
                }
                Tok::Other('}') => {
                    depth -= 1;
                    if depth == 0 {
                        break;
                    }
                }
                Tok::Other(',') if depth == 1 => item_start = true,
                Tok::Ident(name) if depth == 1 && item_start => {
                    out.push((name.clone(), *line));
                    item_start = false;
                }
                _ if depth == 1 => item_start = false,
                _ => {}
            }
        }
        out
    };

    // Inline `mod name { .. }` blocks deepen the module path that `super::` climbs.
    let mut inline: Vec<usize> = Vec::new();
    let mut depth = 0usize;
    let mut out = Vec::new();
    let mut k = 0;
    while k < t.len() {
        match &t[k].0 {
            Tok::Other('{') => {
                if k >= 2 && ident(k - 2) == Some("mod") && ident(k - 1).is_some() {
                    inline.push(depth);
                }
                depth += 1;
            }
            Tok::Other('}') => {
                depth = depth.saturating_sub(1);
                if inline.last() == Some(&depth) {
                    inline.pop();
                }
            }
            Tok::Ident(kw) if (kw == "crate" || kw == "super") && is(k + 1, Tok::Punct("::")) => {
                let after_path = k > 0 && is(k - 1, Tok::Punct("::"));
                let mut next = k;
                let at_root = if kw == "crate" {
                    next += 2;
                    true
                } else {
                    let mut climbs = 0;
                    while ident(next) == Some("super") && is(next + 1, Tok::Punct("::")) {
                        climbs += 1;
                        next += 2;
                    }
                    climbs == file.module.len() + inline.len()
                };
                if at_root && !after_path {
                    for (name, line) in heads(next) {
                        if let Some(to) = resolve(&name) {
                            out.push(Reference {
                                to,
                                at: format!("{}:{line}", file.path),
                            });
                        }
                    }
                }
                k = next;
                continue;
            }
            _ => {}
        }
        k += 1;
    }
    out
}

/// Every reference from a library file under one of `dirs` to one of `targets`.
fn violations(dirs: &[&str], targets: &[&str]) -> Vec<String> {
    let files = library();
    let (modules, reexports) = top_level(&files);
    for m in targets {
        assert!(
            modules.contains(*m),
            "no module {m} in src/: update this rule"
        );
    }
    let mut found = Vec::new();
    for f in files.iter().filter(|f| dirs.contains(&f.top.as_str())) {
        for r in references(f, &modules, &reexports) {
            if targets.contains(&r.to.as_str()) && r.to != f.top {
                found.push(format!("{}: uses crate::{}", r.at, r.to));
            }
        }
    }
    found
}

/// Every use of a token matching `hit` in the library, as `path:line: what`.
fn token_uses(hit: impl Fn(&[(Tok, usize)], usize) -> Option<String>) -> Vec<String> {
    let mut found = Vec::new();
    for f in library() {
        for k in 0..f.tokens.len() {
            if let Some(what) = hit(&f.tokens, k) {
                found.push(format!("{}:{}: {what}", f.path, f.tokens[k].1));
            }
        }
    }
    found
}

#[track_caller]
fn assert_none(rule: &str, found: Vec<String>) {
    assert!(
        found.is_empty(),
        "{rule}: {} violations\n  {}",
        found.len(),
        found.join("\n  ")
    );
}

#[test]
fn accel_is_pure_geometry() {
    assert_none(
        "src/accel must not use scene, trace, render, debug or stats",
        violations(&["accel"], &["scene", "trace", "render", "debug", "stats"]),
    );
}

#[test]
fn debug_only_observes() {
    assert_none(
        "trace, accel, film, shade and sampling must not use debug",
        violations(&["trace", "accel", "film", "shade", "sampling"], &["debug"]),
    );
}

#[test]
fn scene_does_not_use_render() {
    assert_none(
        "src/scene must not use render",
        violations(&["scene"], &["render"]),
    );
}

#[test]
fn scene_does_not_use_shade() {
    assert_none(
        "src/scene must not use shade",
        violations(&["scene"], &["shade"]),
    );
}

#[test]
fn library_does_not_use_clap() {
    assert_none(
        "clap belongs to the binary (src/main.rs, src/bin/)",
        token_uses(|t, k| (t[k].0 == Tok::Ident("clap".into())).then(|| "clap".into())),
    );
}

#[test]
fn library_does_not_print() {
    assert_none(
        "terminal output belongs to the binary (src/main.rs, src/bin/)",
        token_uses(|t, k| match &t[k].0 {
            Tok::Ident(m) if (m == "println" || m == "eprintln") => {
                (t.get(k + 1).map(|x| &x.0) == Some(&Tok::Other('!'))).then(|| format!("{m}!"))
            }
            _ => None,
        }),
    );
}

#[test]
fn top_level_modules_form_no_cycle() {
    let files = library();
    let (modules, reexports) = top_level(&files);
    // module -> module it uses -> the first place it does so
    let mut edges: BTreeMap<String, BTreeMap<String, String>> = BTreeMap::new();
    for f in files.iter().filter(|f| !f.top.is_empty()) {
        for r in references(f, &modules, &reexports) {
            if r.to != f.top {
                edges
                    .entry(f.top.clone())
                    .or_default()
                    .entry(r.to)
                    .or_insert(r.at);
            }
        }
    }
    let mut found = Vec::new();
    for component in strongly_connected(&modules, &edges) {
        let members: BTreeSet<&String> = component.iter().collect();
        let mut lines = vec![format!("cycle among {}", component.join(", "))];
        for from in &component {
            for (to, at) in &edges[from] {
                if members.contains(to) {
                    lines.push(format!("    {from} -> {to} ({at})"));
                }
            }
        }
        found.push(lines.join("\n"));
    }
    assert_none("the top-level modules must form no import cycle", found);
}

/// The strongly connected components of more than one module (Tarjan).
fn strongly_connected(
    nodes: &BTreeSet<String>,
    edges: &BTreeMap<String, BTreeMap<String, String>>,
) -> Vec<Vec<String>> {
    struct State<'a> {
        edges: &'a BTreeMap<String, BTreeMap<String, String>>,
        index: BTreeMap<&'a str, usize>,
        low: BTreeMap<&'a str, usize>,
        stack: Vec<&'a str>,
        on_stack: BTreeSet<&'a str>,
        out: Vec<Vec<String>>,
    }
    fn visit<'a>(s: &mut State<'a>, v: &'a str) {
        let i = s.index.len();
        s.index.insert(v, i);
        s.low.insert(v, i);
        s.stack.push(v);
        s.on_stack.insert(v);
        let edges = s.edges;
        for w in edges.get(v).into_iter().flat_map(|e| e.keys()) {
            if !s.index.contains_key(w.as_str()) {
                visit(s, w);
                let low = s.low[v].min(s.low[w.as_str()]);
                s.low.insert(v, low);
            } else if s.on_stack.contains(w.as_str()) {
                let low = s.low[v].min(s.index[w.as_str()]);
                s.low.insert(v, low);
            }
        }
        if s.low[v] == s.index[v] {
            let mut component = Vec::new();
            while let Some(w) = s.stack.pop() {
                s.on_stack.remove(w);
                component.push(w.to_owned());
                if w == v {
                    break;
                }
            }
            if component.len() > 1 {
                component.sort();
                s.out.push(component);
            }
        }
    }
    let mut s = State {
        edges,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on_stack: BTreeSet::new(),
        out: Vec::new(),
    };
    for v in nodes {
        if !s.index.contains_key(v.as_str()) {
            visit(&mut s, v);
        }
    }
    s.out
}

#[test]
fn the_scanner_sees_grouped_and_super_paths() {
    let tokens = tokenize(
        "// crate::debug in a comment\nuse crate::{film, trace::geometry::X};\nuse super::super::scene::Y;\nlet s = \"crate::render\";\nmod inner { use super::super::super::stats; }\n",
    );
    let file = Source {
        path: "src/a/b.rs".into(),
        top: "a".into(),
        module: vec!["a".into(), "b".into()],
        tokens,
    };
    let modules = ["a", "film", "trace", "scene", "render", "debug", "stats"]
        .map(String::from)
        .into_iter()
        .collect();
    let refs: Vec<String> = references(&file, &modules, &BTreeMap::new())
        .into_iter()
        .map(|r| format!("{} {}", r.to, r.at))
        .collect();
    assert_eq!(
        refs,
        [
            "film src/a/b.rs:2",
            "trace src/a/b.rs:2",
            "scene src/a/b.rs:3",
            "stats src/a/b.rs:5"
        ]
    );
}
