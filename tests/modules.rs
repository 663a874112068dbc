//! The module graph of each crate has no cycle: data and dependencies flow one way (scene file
//! -> format -> scene -> world -> render scene -> integrators), so that a module can be read,
//! tested and changed with only the modules below it in mind.
//!
//! A module's arrows are the `crate::name` paths in its files (its submodules included, doc
//! comments and unit tests not), `name` being another top-level module of the same crate.
//!
//! And no source file grows past [`MAX_LINES`] before its unit tests: one that does holds more
//! than one idea, and is split by idea (issue 42).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// `crate::a` paths in `text` (code only), including `use crate::{a::X, b}` groups.
fn crate_paths(text: &str) -> BTreeSet<String> {
    // Unit tests may reach anywhere; comments are not arrows.
    let code = text.split("#[cfg(test)]").next().unwrap_or("");
    let code: String =
        code.lines().filter(|l| !l.trim_start().starts_with("//")).collect::<Vec<_>>().join("\n");
    let mut out = BTreeSet::new();
    let ident = |s: &str| s.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect::<String>();
    let mut rest = code.as_str();
    while let Some(i) = rest.find("crate::") {
        let after = &rest[i + "crate::".len()..];
        let start_ok = i == 0 || !rest[..i].ends_with(|c: char| c.is_alphanumeric() || c == '_');
        if start_ok {
            if let Some(group) = after.strip_prefix('{') {
                // Top-level names of the group: split at commas outside nested braces.
                let mut depth = 0;
                let mut item = String::new();
                for c in group.chars() {
                    match c {
                        '{' => depth += 1,
                        '}' if depth == 0 => break,
                        '}' => depth -= 1,
                        ',' if depth == 0 => {
                            out.insert(ident(item.trim()));
                            item.clear();
                            continue;
                        }
                        _ => {}
                    }
                    item.push(c);
                }
                out.insert(ident(item.trim()));
            } else {
                out.insert(ident(after));
            }
        }
        rest = after;
    }
    out.retain(|n| !n.is_empty());
    out
}

/// The `.rs` files under `src` that are not unit tests, sorted.
fn source_files(src: &Path) -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|x| x == "rs") {
                out.push(p);
            }
        }
    }
    let mut files = Vec::new();
    walk(src, &mut files);
    // A unit-test module in a file of its own (`#[cfg(test)] mod tests;`) is test code too.
    let tests: BTreeSet<PathBuf> = files.iter().flat_map(|f| test_files(f)).collect();
    files.retain(|f| !tests.contains(f));
    files.sort();
    files
}

/// The files of `src`, by top-level module (`a.rs` and everything under `a/`); the crate root's
/// own files (`lib.rs`, `main.rs`) are left out.
fn modules(src: &Path) -> BTreeMap<String, Vec<PathBuf>> {
    let mut by_module: BTreeMap<String, Vec<PathBuf>> = BTreeMap::new();
    for f in source_files(src) {
        let rel = f.strip_prefix(src).unwrap();
        let first = rel.components().next().unwrap().as_os_str().to_string_lossy().into_owned();
        let name = first.trim_end_matches(".rs").to_owned();
        if rel.components().count() == 1 && (name == "lib" || name == "main") {
            continue;
        }
        by_module.entry(name).or_default().push(f);
    }
    by_module
}

/// The files of the modules that `file` declares as `#[cfg(test)] mod name;`.
fn test_files(file: &Path) -> Vec<PathBuf> {
    let text = std::fs::read_to_string(file).unwrap();
    let stem = file.file_stem().unwrap().to_string_lossy();
    // Where `file`'s submodules live: beside it for a `mod.rs` or crate root, else in a folder
    // named after it.
    let dir = match &*stem {
        "mod" | "lib" | "main" => file.parent().unwrap().to_path_buf(),
        _ => file.with_extension(""),
    };
    let lines: Vec<&str> = text.lines().map(str::trim).collect();
    lines
        .windows(2)
        .filter(|w| w[0] == "#[cfg(test)]")
        .filter_map(|w| w[1].strip_prefix("mod ")?.strip_suffix(';'))
        .flat_map(|name| [dir.join(format!("{name}.rs")), dir.join(name).join("mod.rs")])
        .collect()
}

/// Arrows between the top-level modules of `src`: (from, to) -> a file that makes it.
fn arrows(src: &Path) -> BTreeMap<(String, String), PathBuf> {
    let mods = modules(src);
    let mut out = BTreeMap::new();
    for (m, files) in &mods {
        for f in files {
            for to in crate_paths(&std::fs::read_to_string(f).unwrap()) {
                if to != *m && mods.contains_key(&to) {
                    out.entry((m.clone(), to)).or_insert_with(|| f.clone());
                }
            }
        }
    }
    out
}

/// A cycle of the graph, as the modules along it, if there is one.
fn find_cycle(arrows: &BTreeMap<(String, String), PathBuf>) -> Option<Vec<String>> {
    let mut next: BTreeMap<&str, Vec<&str>> = BTreeMap::new();
    for (a, b) in arrows.keys() {
        next.entry(a).or_default().push(b);
    }
    // Depth-first search; 1 = on the current path, 2 = done.
    fn visit<'a>(
        v: &'a str,
        next: &BTreeMap<&'a str, Vec<&'a str>>,
        state: &mut BTreeMap<&'a str, u8>,
        path: &mut Vec<&'a str>,
    ) -> Option<Vec<String>> {
        state.insert(v, 1);
        path.push(v);
        for &w in next.get(v).into_iter().flatten() {
            match state.get(w) {
                Some(1) => {
                    let at = path.iter().position(|&p| p == w).unwrap();
                    let mut cycle: Vec<String> = path[at..].iter().map(|s| s.to_string()).collect();
                    cycle.push(w.to_string());
                    return Some(cycle);
                }
                Some(_) => {}
                None => {
                    if let Some(c) = visit(w, next, state, path) {
                        return Some(c);
                    }
                }
            }
        }
        path.pop();
        state.insert(v, 2);
        None
    }
    let mut state = BTreeMap::new();
    for &v in next.keys() {
        if !state.contains_key(v)
            && let Some(c) = visit(v, &next, &mut state, &mut Vec::new())
        {
            return Some(c);
        }
    }
    None
}

/// The most lines a source file holds before its unit tests.
const MAX_LINES: usize = 600;

/// The lines of `text` before its first line that starts with `#[cfg(test)]` (the unit tests
/// that close a file; an indented one inside the code does not end it).
fn lines_before_tests(text: &str) -> usize {
    text.lines().take_while(|l| !l.starts_with("#[cfg(test)]")).count()
}

fn check(crate_src: &str) {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join(crate_src);
    let arrows = arrows(&src);
    assert!(
        arrows.len() > 5,
        "{}: too few arrows found ({}): is the parser reading it?",
        src.display(),
        arrows.len()
    );
    if let Some(cycle) = find_cycle(&arrows) {
        let steps: Vec<String> = cycle
            .windows(2)
            .map(|w| {
                let file = &arrows[&(w[0].clone(), w[1].clone())];
                format!("{} -> {} ({})", w[0], w[1], file.strip_prefix(&src).unwrap().display())
            })
            .collect();
        panic!("{}: the modules form a cycle: {}", src.display(), steps.join(", "));
    }
}

#[test]
fn engine_modules_have_no_cycle() {
    check("engine/src");
}

#[test]
fn integrator_modules_have_no_cycle() {
    check("integrator/src");
}

#[test]
fn cli_modules_have_no_cycle() {
    check("src");
}

/// Every source file of the three crates, unit tests in files of their own left out, holds at
/// most [`MAX_LINES`] lines before its unit tests; the message names every file over.
#[test]
fn no_source_file_is_over_600_lines() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut over = Vec::new();
    let mut seen = 0;
    for src in ["engine/src", "integrator/src", "src"] {
        for f in source_files(&root.join(src)) {
            seen += 1;
            let n = lines_before_tests(&std::fs::read_to_string(&f).unwrap());
            if n > MAX_LINES {
                over.push(format!("{} ({n} lines)", f.strip_prefix(root).unwrap().display()));
            }
        }
    }
    assert!(seen > 100, "only {seen} source files found: is the walk reading the crates?");
    assert!(
        over.is_empty(),
        "{} source files are over {MAX_LINES} lines before their unit tests (split each by idea): {}",
        over.len(),
        over.join(", ")
    );
}

#[test]
fn lines_are_counted_up_to_the_unit_tests() {
    assert_eq!(lines_before_tests("a\n\n    #[cfg(test)]\n    fn f() {}\n#[cfg(test)]\nmod tests {}\n"), 4);
    assert_eq!(lines_before_tests("a\nb\n"), 2);
}

#[test]
fn paths_are_read_from_groups_and_not_from_comments() {
    let text = "use crate::{a::X, b::{Y, Z}, c};\n// crate::d\nfn f() { crate::e::g(); notcrate::h(); }\n\
                #[cfg(test)]\nmod tests { use crate::i; }";
    let found: Vec<String> = crate_paths(text).into_iter().collect();
    assert_eq!(found, ["a", "b", "c", "e"]);
}

#[test]
fn test_modules_in_files_of_their_own_are_found() {
    let dir = std::env::temp_dir().join(format!("pathwave-modules-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("a")).unwrap();
    std::fs::write(dir.join("a.rs"), "mod inner;\n#[cfg(test)]\nmod tests;\n").unwrap();
    std::fs::write(dir.join("mod.rs"), "#[cfg(test)]\n  mod checks;\nmod kept;\n").unwrap();
    let mut found = test_files(&dir.join("a.rs"));
    found.extend(test_files(&dir.join("mod.rs")));
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(
        found,
        [
            dir.join("a/tests.rs"),
            dir.join("a/tests/mod.rs"),
            dir.join("checks.rs"),
            dir.join("checks/mod.rs")
        ]
    );
}
