//! No import cycle between the modules of a crate, in every crate of the workspace (`src/`).
//!
//! Each crate's module tree is read from its `mod` declarations (files and inline modules,
//! starting at `src/lib.rs` and `src/main.rs`), and every path that names an item of the same
//! crate becomes a reference from the module it is written in to the module it resolves to:
//! the paths of `use` declarations (trees expanded, `self`, `super`, `crate` and names bound by
//! other `use`s followed, so a re-export resolves to the module that defines the item) and the
//! paths written in code that start with `crate::`, `super::` or `self::`. Comments and string
//! literals are skipped, so doc links do not count.
//!
//! A reference from module M to module T counts between the two children of their deepest
//! common ancestor that contain them: `ocp::mesh::f` using `crate::error::E` is the edge
//! `ocp → error` among the crate root's children, `ocp::mesh` using `super::transcription::X`
//! the edge `mesh → transcription` among `ocp`'s children. A module referring to its own
//! ancestors or descendants adds no edge (a parent declares and re-exports its children). The
//! sibling graphs must be acyclic: then the modules of every level form layers, each depending
//! only on the ones below it.
//!
//! Limitation (by design, to stay small): names brought in by glob imports (`use x::*`) are
//! not followed further than the glob itself, and macro-generated paths are not seen.

use std::collections::{BTreeMap, BTreeSet, VecDeque};
use std::path::{Path, PathBuf};

/// A module's path from its crate root (empty for the root).
type ModPath = Vec<String>;

#[derive(Debug, Clone, PartialEq)]
enum Tok {
    Ident(String),
    PathSep,
    Open,
    Close,
    Semi,
    Comma,
    Star,
    Other(char),
}

/// The tokens of Rust source that matter for paths, with their line numbers; comments, string,
/// char and numeric literals and lifetimes are dropped.
fn tokens(src: &str) -> Vec<(Tok, usize)> {
    let c: Vec<char> = src.chars().collect();
    let n = c.len();
    let (mut i, mut line) = (0, 1);
    let mut out = Vec::new();
    let ident_start = |ch: char| ch == '_' || ch.is_alphabetic();
    let ident_cont = |ch: char| ch == '_' || ch.is_alphanumeric();
    // Skips a (raw, when `hashes` is Some) string whose opening quote is at `i`.
    let skip_string = |mut i: usize, hashes: Option<usize>, line: &mut usize| -> usize {
        i += 1;
        while i < n {
            match (c[i], hashes) {
                ('\n', _) => *line += 1,
                ('\\', None) => {
                    if c.get(i + 1) == Some(&'\n') {
                        *line += 1;
                    }
                    i += 1;
                }
                ('"', None) => return i + 1,
                ('"', Some(h)) if (1..=h).all(|k| c.get(i + k) == Some(&'#')) => {
                    return i + 1 + h;
                }
                _ => {}
            }
            i += 1;
        }
        n
    };
    while i < n {
        let ch = c[i];
        if ch == '\n' {
            line += 1;
            i += 1;
        } else if ch.is_whitespace() {
            i += 1;
        } else if ch == '/' && c.get(i + 1) == Some(&'/') {
            while i < n && c[i] != '\n' {
                i += 1;
            }
        } else if ch == '/' && c.get(i + 1) == Some(&'*') {
            let mut depth = 0;
            while i < n {
                if c[i] == '/' && c.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if c[i] == '*' && c.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    if c[i] == '\n' {
                        line += 1;
                    }
                    i += 1;
                }
            }
        } else if ch == '"' {
            i = skip_string(i, None, &mut line);
        } else if ch == '\'' {
            if c.get(i + 1) == Some(&'\\') {
                // An escaped char literal: past the escaped char, up to the closing quote.
                i += 3;
                while i < n && c[i] != '\'' {
                    i += 1;
                }
                i += 1;
            } else if c.get(i + 2) == Some(&'\'') {
                i += 3;
            } else {
                // A lifetime or label: its name is lexed as an identifier next.
                i += 1;
            }
        } else if ident_start(ch) {
            let s = i;
            while i < n && ident_cont(c[i]) {
                i += 1;
            }
            let word: String = c[s..i].iter().collect();
            let prefix = matches!(word.as_str(), "r" | "br" | "cr");
            let hashes = c[i..].iter().take_while(|&&h| h == '#').count();
            if prefix && c.get(i + hashes) == Some(&'"') {
                i = skip_string(i + hashes, Some(hashes), &mut line);
            } else if matches!(word.as_str(), "b" | "c") && c.get(i) == Some(&'"') {
                i = skip_string(i, None, &mut line);
            } else if word == "b" && c.get(i) == Some(&'\'') {
                // A byte literal: the char-literal branch skips it.
            } else if word == "r" && hashes == 1 && c.get(i + 1).is_some_and(|&h| ident_start(h)) {
                // A raw identifier (`r#type`): the identifier follows.
                i += 1;
            } else {
                out.push((Tok::Ident(word), line));
            }
        } else if ch.is_ascii_digit() {
            while i < n && ident_cont(c[i]) {
                i += 1;
            }
        } else {
            let t = match ch {
                ':' if c.get(i + 1) == Some(&':') => {
                    i += 1;
                    Tok::PathSep
                }
                '{' => Tok::Open,
                '}' => Tok::Close,
                ';' => Tok::Semi,
                ',' => Tok::Comma,
                '*' => Tok::Star,
                other => Tok::Other(other),
            };
            out.push((t, line));
            i += 1;
        }
    }
    out
}

/// One leaf of a `use` tree: its full path, the name it binds (none for globs and `as _`).
struct UseLeaf {
    path: Vec<String>,
    binds: Option<String>,
    line: usize,
}

/// Parses the `use` tree starting at `toks[*i]` (after the `use` keyword) under `prefix`.
fn use_tree(toks: &[(Tok, usize)], i: &mut usize, prefix: &[String], out: &mut Vec<UseLeaf>) {
    let mut path = prefix.to_vec();
    let line = toks.get(*i).map_or(0, |t| t.1);
    if toks.get(*i).map(|t| &t.0) == Some(&Tok::PathSep) {
        // `::name`: an external crate.
        path.push("::".into());
        *i += 1;
    }
    loop {
        match toks.get(*i).map(|t| &t.0) {
            Some(Tok::Ident(s)) if s == "self" && !path.is_empty() => *i += 1,
            Some(Tok::Ident(s)) => {
                path.push(s.clone());
                *i += 1;
            }
            Some(Tok::Star) => {
                *i += 1;
                out.push(UseLeaf {
                    path,
                    binds: None,
                    line,
                });
                return;
            }
            Some(Tok::Open) => {
                *i += 1;
                while !matches!(toks.get(*i).map(|t| &t.0), Some(Tok::Close) | None) {
                    let start = *i;
                    use_tree(toks, i, &path, out);
                    if toks.get(*i).map(|t| &t.0) == Some(&Tok::Comma) || *i == start {
                        *i += 1;
                    }
                }
                *i += 1;
                return;
            }
            _ => break,
        }
        if toks.get(*i).map(|t| &t.0) == Some(&Tok::PathSep) {
            *i += 1;
        } else {
            break;
        }
    }
    let mut binds = path.last().cloned();
    if let Some(Tok::Ident(kw)) = toks.get(*i).map(|t| &t.0)
        && kw == "as"
    {
        binds = match toks.get(*i + 1).map(|t| &t.0) {
            Some(Tok::Ident(name)) if name != "_" => Some(name.clone()),
            _ => None,
        };
        *i += 2;
    }
    out.push(UseLeaf { path, binds, line });
}

/// A path written in a module, as written.
struct Reference {
    from: ModPath,
    path: Vec<String>,
    file: String,
    line: usize,
}

/// The module tree of one crate and the paths written in it.
#[derive(Default)]
struct Crate {
    /// Every module, with the names its `use` declarations bind (name → path as written).
    modules: BTreeMap<ModPath, BTreeMap<String, Vec<String>>>,
    /// Modules declared under `#[cfg(test)]`.
    tests: BTreeSet<ModPath>,
    references: Vec<Reference>,
}

impl Crate {
    /// Reads the crate whose root files are `roots` (paths as `read` knows them); `read`
    /// returns a file's text, or `None` if there is no such file.
    fn read(roots: &[PathBuf], read: &dyn Fn(&Path) -> Option<String>) -> Crate {
        let mut krate = Crate::default();
        krate.modules.insert(vec![], BTreeMap::new());
        // (file, module path, directory of its child module files)
        let mut queue: VecDeque<(PathBuf, ModPath, PathBuf)> = roots
            .iter()
            .filter(|r| read(r).is_some())
            .map(|r| {
                (
                    r.clone(),
                    vec![],
                    r.parent().unwrap_or(Path::new("")).into(),
                )
            })
            .collect();
        while let Some((file, module, dir)) = queue.pop_front() {
            let Some(text) = read(&file) else { continue };
            let toks = tokens(&text);
            // Inline modules open at a brace depth: (name, depth inside its braces).
            let mut inline: Vec<(String, usize)> = Vec::new();
            let mut depth = 0usize;
            let here = |inline: &[(String, usize)]| -> ModPath {
                let mut m = module.clone();
                m.extend(inline.iter().map(|(n, _)| n.clone()));
                m
            };
            // Set by `#[cfg(test)]` until the item it applies to starts.
            let mut cfg_test = false;
            let mut i = 0;
            while i < toks.len() {
                let prev_sep = i > 0 && toks[i - 1].0 == Tok::PathSep;
                let ident =
                    |k: usize, w: &str| matches!(toks.get(k), Some((Tok::Ident(s), _)) if s == w);
                if ident(i, "cfg")
                    && toks.get(i + 1).map(|t| &t.0) == Some(&Tok::Other('('))
                    && ident(i + 2, "test")
                    && toks.get(i + 3).map(|t| &t.0) == Some(&Tok::Other(')'))
                {
                    cfg_test = true;
                }
                if matches!(toks[i].0, Tok::Open | Tok::Close | Tok::Semi) {
                    cfg_test = false;
                }
                match &toks[i].0 {
                    Tok::Open => depth += 1,
                    Tok::Close => {
                        if inline.last().is_some_and(|&(_, d)| d == depth) {
                            inline.pop();
                        }
                        depth = depth.saturating_sub(1);
                    }
                    Tok::Ident(kw) if kw == "mod" && !prev_sep => {
                        if let (Some((Tok::Ident(name), _)), Some((next, _))) =
                            (toks.get(i + 1), toks.get(i + 2))
                        {
                            let mut child = here(&inline);
                            child.push(name.clone());
                            krate.modules.entry(child.clone()).or_default();
                            if cfg_test {
                                krate.tests.insert(child.clone());
                            }
                            if *next == Tok::Open {
                                depth += 1;
                                inline.push((name.clone(), depth));
                                i += 3;
                                continue;
                            }
                            if *next == Tok::Semi {
                                let mut d = dir.clone();
                                d.extend(inline.iter().map(|(n, _)| n.as_str()));
                                let flat = d.join(format!("{name}.rs"));
                                let (f, sub) = if read(&flat).is_some() {
                                    (flat, d.join(name))
                                } else {
                                    (d.join(name).join("mod.rs"), d.join(name))
                                };
                                queue.push_back((f, child, sub));
                            }
                        }
                    }
                    Tok::Ident(kw) if kw == "use" && !prev_sep => {
                        i += 1;
                        let mut leaves = Vec::new();
                        use_tree(&toks, &mut i, &[], &mut leaves);
                        let from = here(&inline);
                        for leaf in leaves {
                            if let Some(name) = &leaf.binds {
                                krate
                                    .modules
                                    .entry(from.clone())
                                    .or_default()
                                    .insert(name.clone(), leaf.path.clone());
                            }
                            krate.references.push(Reference {
                                from: from.clone(),
                                path: leaf.path,
                                file: file.display().to_string(),
                                line: leaf.line,
                            });
                        }
                        continue;
                    }
                    Tok::Ident(kw)
                        if matches!(kw.as_str(), "crate" | "super" | "self")
                            && !prev_sep
                            && toks.get(i + 1).map(|t| &t.0) == Some(&Tok::PathSep) =>
                    {
                        let line = toks[i].1;
                        let mut path = vec![kw.clone()];
                        let mut j = i + 1;
                        while toks.get(j).map(|t| &t.0) == Some(&Tok::PathSep) {
                            match toks.get(j + 1) {
                                Some((Tok::Ident(s), _)) => path.push(s.clone()),
                                _ => break,
                            }
                            j += 2;
                        }
                        krate.references.push(Reference {
                            from: here(&inline),
                            path,
                            file: file.display().to_string(),
                            line,
                        });
                        i = j;
                        continue;
                    }
                    _ => {}
                }
                i += 1;
            }
        }
        krate
    }

    /// The absolute path (from the crate root) of `path` written in module `from`; `None` for
    /// paths into other crates.
    fn absolute(&self, from: &ModPath, path: &[String], depth: usize) -> Option<Vec<String>> {
        let (first, rest) = path.split_first()?;
        match first.as_str() {
            "crate" => Some(rest.to_vec()),
            "self" | "super" => {
                let mut base = from.clone();
                let mut k = 0;
                while k < path.len() && matches!(path[k].as_str(), "self" | "super") {
                    if path[k] == "super" {
                        base.pop()?;
                    }
                    k += 1;
                }
                base.extend_from_slice(&path[k..]);
                Some(base)
            }
            name => {
                let mut child = from.clone();
                child.push(name.to_string());
                if self.modules.contains_key(&child) {
                    child.extend_from_slice(rest);
                    return Some(child);
                }
                let target = self.modules.get(from)?.get(name)?;
                if depth > 16 || target.first().map(String::as_str) == Some(name) {
                    return None;
                }
                let mut abs = self.absolute(from, target, depth + 1)?;
                abs.extend_from_slice(rest);
                Some(abs)
            }
        }
    }

    /// The module that defines what the absolute path `abs` names: its longest prefix that is
    /// a module, following names bound by `use` (re-exports) on the way.
    fn module_of(&self, abs: &[String], depth: usize) -> ModPath {
        let mut cur: ModPath = vec![];
        for (k, seg) in abs.iter().enumerate() {
            let mut next = cur.clone();
            next.push(seg.clone());
            if self.modules.contains_key(&next) {
                cur = next;
                continue;
            }
            if depth < 16
                && let Some(target) = self.modules.get(&cur).and_then(|u| u.get(seg))
                && let Some(mut t) = self.absolute(&cur, target, depth + 1)
            {
                t.extend_from_slice(&abs[k + 1..]);
                return self.module_of(&t, depth + 1);
            }
            break;
        }
        cur
    }

    /// The sibling edges (from child, to child, both full module paths) with the first
    /// reference that makes each, as "file:line `path`".
    fn edges(&self) -> BTreeMap<(ModPath, ModPath), String> {
        let mut out = BTreeMap::new();
        for r in &self.references {
            if (0..=r.from.len()).any(|k| self.tests.contains(&r.from[..k])) {
                continue;
            }
            let Some(abs) = self.absolute(&r.from, &r.path, 0) else {
                continue;
            };
            let to = self.module_of(&abs, 0);
            let common = r.from.iter().zip(&to).take_while(|(a, b)| a == b).count();
            if common == r.from.len() || common == to.len() {
                continue;
            }
            let key = (r.from[..=common].to_vec(), to[..=common].to_vec());
            out.entry(key)
                .or_insert_with(|| format!("{}:{} `{}`", r.file, r.line, r.path.join("::")));
        }
        out
    }

    /// Every cycle of the sibling graphs, one per strongly connected component, as lines
    /// "a → b → a" followed by the reference behind each edge.
    fn cycles(&self) -> Vec<String> {
        let edges = self.edges();
        let mut next: BTreeMap<&ModPath, BTreeSet<&ModPath>> = BTreeMap::new();
        for (a, b) in edges.keys() {
            next.entry(a).or_default().insert(b);
        }
        // Breadth-first search from s: every reached node with its predecessor.
        fn reach<'a>(
            next: &BTreeMap<&'a ModPath, BTreeSet<&'a ModPath>>,
            s: &'a ModPath,
        ) -> BTreeMap<&'a ModPath, &'a ModPath> {
            let mut pred = BTreeMap::new();
            let mut queue = VecDeque::from([s]);
            while let Some(u) = queue.pop_front() {
                for &v in next.get(u).into_iter().flatten() {
                    if !pred.contains_key(v) {
                        pred.insert(v, u);
                        queue.push_back(v);
                    }
                }
            }
            pred
        }
        let name = |m: &ModPath| m.join("::");
        let mut done: BTreeSet<&ModPath> = BTreeSet::new();
        let mut out = Vec::new();
        for &s in next.keys() {
            if done.contains(s) {
                continue;
            }
            let pred = reach(&next, s);
            if !pred.contains_key(s) {
                continue;
            }
            // The shortest cycle through s, walked back from s's predecessor.
            let mut cycle = vec![s];
            let mut u = pred[s];
            while u != s {
                cycle.push(u);
                u = pred[u];
            }
            cycle.push(s);
            cycle.reverse();
            // Everything on a cycle with s is in its component: report the component once.
            let component: Vec<&ModPath> = pred
                .keys()
                .copied()
                .filter(|v| reach(&next, v).contains_key(s))
                .collect();
            done.extend(&component);
            let component: Vec<String> = component.iter().map(|m| name(m)).collect();
            let mut text = cycle
                .iter()
                .map(|m| name(m))
                .collect::<Vec<_>>()
                .join(" → ");
            text.push_str(&format!(" (the cycles join {})", component.join(", ")));
            for w in cycle.windows(2) {
                let why = &edges[&(w[0].clone(), w[1].clone())];
                text.push_str(&format!("\n    {} → {}: {why}", name(w[0]), name(w[1])));
            }
            out.push(text);
        }
        out
    }
}

/// The crates of the workspace: the root package and every directory beside it with a
/// `Cargo.toml` and a `src/`.
fn workspace_crates() -> Vec<PathBuf> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let mut dirs = vec![root.clone()];
    let mut members: Vec<PathBuf> = std::fs::read_dir(&root)
        .expect("the workspace root is readable")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.join("Cargo.toml").is_file() && p.join("src").is_dir())
        .collect();
    members.sort();
    dirs.extend(members);
    dirs
}

fn read_file(p: &Path) -> Option<String> {
    std::fs::read_to_string(p).ok()
}

#[test]
fn no_module_cycle_in_any_crate() {
    let mut report = Vec::new();
    let mut modules = 0;
    for dir in workspace_crates() {
        let src = dir.join("src");
        let krate = Crate::read(&[src.join("lib.rs"), src.join("main.rs")], &read_file);
        modules += krate.modules.len();
        let root = format!("{}/", env!("CARGO_MANIFEST_DIR"));
        for c in krate.cycles() {
            let name = match dir.strip_prefix(&root) {
                Ok(member) if !member.as_os_str().is_empty() => member.display().to_string(),
                _ => "root package".to_string(),
            };
            report.push(format!("{name}: {}", c.replace(&root, "")));
        }
    }
    // The scan must have seen the workspace (a broken walk would find no cycle either).
    assert!(modules > 100, "only {modules} modules found");
    assert!(
        report.is_empty(),
        "import cycles between modules:\n{}",
        report.join("\n")
    );
}

/// Reads a crate from in-memory files.
fn synthetic(files: &[(&str, &str)]) -> Crate {
    let map: BTreeMap<PathBuf, String> = files
        .iter()
        .map(|(p, t)| (PathBuf::from(p), t.to_string()))
        .collect();
    Crate::read(&[PathBuf::from("src/lib.rs")], &|p: &Path| {
        map.get(p).cloned()
    })
}

#[test]
fn a_cycle_through_a_nested_module_and_a_re_export_is_found() {
    let k = synthetic(&[
        ("src/lib.rs", "mod a;\nmod b;\npub use a::Thing;\n"),
        ("src/a.rs", "mod inner;\npub struct Thing;\n"),
        ("src/a/inner.rs", "fn f() -> crate::b::Other { todo() }\n"),
        ("src/b.rs", "use crate::Thing;\npub struct Other(Thing);\n"),
    ]);
    let c = k.cycles();
    assert_eq!(c.len(), 1, "{c:?}");
    assert!(c[0].starts_with("a → b → a"), "{}", c[0]);
    assert!(
        c[0].contains("src/a/inner.rs:1 `crate::b::Other`"),
        "{}",
        c[0]
    );
    assert!(c[0].contains("src/b.rs:1 `crate::Thing`"), "{}", c[0]);
}

#[test]
fn a_cycle_among_the_children_of_a_module_is_found_at_that_level() {
    let k = synthetic(&[
        ("src/lib.rs", "pub mod ocp;\n"),
        (
            "src/ocp/mod.rs",
            "pub mod mesh;\npub mod tr;\nmod x { pub mod y {} }\n",
        ),
        ("src/ocp/mesh.rs", "use super::tr::{self, Mesh as M};\n"),
        (
            "src/ocp/tr.rs",
            "pub struct Mesh;\nfn g() { let _ = super::mesh::f(); }\n",
        ),
    ]);
    let c = k.cycles();
    assert_eq!(c.len(), 1, "{c:?}");
    assert!(
        c[0].starts_with("ocp::mesh → ocp::tr → ocp::mesh"),
        "{}",
        c[0]
    );
}

#[test]
fn layers_comments_strings_and_parent_child_references_are_no_cycle() {
    let k = synthetic(&[
        (
            "src/lib.rs",
            "mod low;\nmod high;\npub use high::H;\n/// [`crate::high::H`]\npub struct R;\n",
        ),
        (
            "src/low.rs",
            "// crate::high::H\nconst S: &str = \"crate::high::H\";\nconst C: char = '{';\n\
             const RAW: &str = r#\"super::high\"#;\nfn f<'a>(x: &'a str) -> &'a str { x }\n\
             pub struct L(crate::R);\n#[cfg(test)]\nmod tests {\n    use super::*;\n    \
             use crate::high::H;\n}\n",
        ),
        (
            "src/high.rs",
            "use crate::low::L;\npub struct H(L);\nmod sub;\n",
        ),
        (
            "src/high/sub.rs",
            "use super::super::low::L;\nuse super::H;\n",
        ),
    ]);
    assert!(k.cycles().is_empty(), "{:?}", k.cycles());
    // The references were seen: high depends on low, not the other way.
    let edges: Vec<(ModPath, ModPath)> = k.edges().into_keys().collect();
    assert_eq!(
        edges,
        vec![(vec!["high".to_string()], vec!["low".to_string()])]
    );
}
