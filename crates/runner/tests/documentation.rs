//! The project's documentation resolves: every relative link in README.md, CHANGELOG.md, docs/*.md and
//! docs/journal/*.md names a file that exists, and no source file cites design notes that are not in the
//! repository (a reader of the code must be able to follow every citation: papers are cited by author and
//! year, the project's own notes live in docs/).

use std::path::{Path, PathBuf};

fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The targets of the Markdown links `[text](target)` in `text` (anchors stripped), skipping URLs.
fn link_targets(text: &str) -> Vec<String> {
    let mut targets = Vec::new();
    let mut rest = text;
    while let Some(start) = rest.find("](") {
        let after = &rest[start + 2..];
        let Some(end) = after.find(')') else { break };
        let target = after[..end].split('#').next().unwrap_or_default().trim();
        if !target.is_empty() && !target.contains("://") {
            targets.push(target.to_string());
        }
        rest = &after[end..];
    }
    targets
}

#[test]
fn relative_links_in_the_readme_and_docs_resolve() {
    let root = workspace_root();
    let mut files = vec![root.join("README.md"), root.join("CHANGELOG.md")];
    let markdown_in = |dir: &str| -> Vec<PathBuf> {
        let mut found: Vec<PathBuf> = std::fs::read_dir(root.join(dir))
            .unwrap_or_else(|e| panic!("{dir}/ exists: {e}"))
            .map(|e| e.expect("readable entry").path())
            .filter(|p| p.extension().is_some_and(|e| e == "md"))
            .collect();
        found.sort();
        found
    };
    let docs = markdown_in("docs");
    assert!(docs.len() >= 4, "docs/ holds the design notes: {docs:?}");
    files.extend(docs);
    files.extend(markdown_in("docs/journal"));
    let mut broken = Vec::new();
    for file in &files {
        let text = std::fs::read_to_string(file).expect("readable Markdown");
        let dir = file.parent().expect("a file has a parent");
        for target in link_targets(&text) {
            if !dir.join(&target).exists() {
                broken.push(format!("{}: {target}", file.display()));
            }
        }
    }
    assert!(broken.is_empty(), "links to missing files: {broken:#?}");
}

#[test]
fn link_targets_are_parsed() {
    assert_eq!(
        link_targets("see [a](docs/a.md#x), [b](https://x.org/y) and ![c](img.png)"),
        vec!["docs/a.md".to_string(), "img.png".to_string()]
    );
}

/// Collects the `.rs` files under `dir`, skipping build output.
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("readable directory") {
        let path = entry.expect("readable entry").path();
        if path.is_dir() {
            if path.file_name().is_some_and(|n| n != "target") {
                rust_files(&path, out);
            }
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

#[test]
fn no_source_cites_notes_outside_the_repository() {
    let mut files = Vec::new();
    rust_files(&workspace_root().join("crates"), &mut files);
    assert!(files.len() > 50, "found the sources: {}", files.len());
    // Spelled in pieces so this file does not match itself.
    let forbidden = [
        ["sur", "vey §"].concat(),
        ["sur", "vey 2."].concat(),
        ["sur", "vey eq"].concat(),
        ["ALGORITHMS", ".md"].concat(),
        ["ARCHITECTURE", ".md"].concat(),
        ["shared/", "design"].concat(),
    ];
    let mut hits = Vec::new();
    for file in &files {
        let text = std::fs::read_to_string(file).expect("readable source");
        for (n, line) in text.lines().enumerate() {
            let lower = line.to_lowercase();
            for f in &forbidden {
                if lower.contains(&f.to_lowercase()) {
                    hits.push(format!("{}:{}: {}", file.display(), n + 1, line.trim()));
                }
            }
        }
    }
    assert!(
        hits.is_empty(),
        "citations a reader of the code cannot follow: {hits:#?}"
    );
}

/// The value a parameter's doc line states as its default, `(default X)` or `(default: X)` with X one word
/// closing the parenthesis; None when the doc states none in that form (e.g. "(default: 2 x element_size)").
fn stated_default(doc: &str) -> Option<String> {
    let i = doc.find("(default")?;
    let rest = doc[i + "(default".len()..].trim_start_matches([':', ' ']);
    let word = &rest[..rest.find(')')?];
    (!word.is_empty() && !word.contains(' ')).then(|| word.to_string())
}

#[test]
fn documented_defaults_match_the_defaults_in_use() {
    // `radlab methods` prints each parameter's default (from the params type) beside its doc line; a number
    // or boolean the doc line states as the default must be that value, for every method (shared doc lines
    // copied from another method's parameters must say that method's defaults).
    let mut wrong = Vec::new();
    for m in radlab_runner::methods::methods() {
        for p in (m.params)() {
            let Some(stated) = stated_default(&p.help) else {
                continue;
            };
            let actual = p.default.trim_matches('"');
            let same = match (stated.parse::<f64>(), actual.parse::<f64>()) {
                (Ok(a), Ok(b)) => a == b,
                (Ok(_), Err(_)) => false,
                (Err(_), _) => stated == actual,
            };
            if !same {
                wrong.push(format!(
                    "{} {}: doc says (default {stated}), default is {}",
                    m.name, p.name, p.default
                ));
            }
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

#[test]
fn each_parameter_is_listed_once() {
    // `radlab methods` lists a method's parameters; a key listed twice (path tracing's per-point and render
    // parameters share `max_depth` and `direct`) leaves the reader to guess which line holds.
    for m in radlab_runner::methods::methods() {
        let names: Vec<String> = (m.params)().into_iter().map(|p| p.name).collect();
        let mut unique = names.clone();
        unique.sort();
        unique.dedup();
        assert_eq!(unique.len(), names.len(), "{}: {names:?}", m.name);
    }
}

#[test]
fn stated_defaults_are_parsed() {
    assert_eq!(
        stated_default("dimensionless (default 0.01)").as_deref(),
        Some("0.01")
    );
    assert_eq!(stated_default("x (default: true)").as_deref(), Some("true"));
    assert_eq!(stated_default("x (default: scene diagonal / 150)"), None);
    assert_eq!(stated_default("no default here"), None);
}

/// Whether `text` holds a date written 2026-12-02.
fn holds_a_date(text: &str) -> bool {
    let b = text.as_bytes();
    b.windows(10).any(|w| {
        w.iter().enumerate().all(|(i, c)| match i {
            4 | 7 => *c == b'-',
            _ => c.is_ascii_digit(),
        })
    })
}

#[test]
fn every_parameter_is_declared_and_its_range_enforced() {
    // Every parameter of every registered method has a help line and a default in `radlab methods` (no dated
    // measurement as help), and a value just outside a declared range is refused naming the key and the range.
    for m in radlab_runner::methods::methods() {
        let params = (m.params)();
        assert!(!params.is_empty(), "{} lists no parameters", m.name);
        for p in &params {
            let what = format!("{} {}", m.name, p.name);
            assert!(!p.help.is_empty(), "{what}: no help");
            assert!(!p.default.is_empty(), "{what}: no default");
            assert!(
                !holds_a_date(&p.help),
                "{what}: a dated help line: {}",
                p.help
            );
            let Some(range) = p.range else { continue };
            let whole = p.kind == "whole number";
            let outside = match (range.min, range.max) {
                (Some((x, true)), _) => x - 1.0,
                (Some((x, false)), _) => x,
                (None, Some((x, true))) => x + 1.0,
                (None, Some((x, false))) => x,
                (None, None) => continue,
            };
            let value = if whole {
                toml::Value::Integer(outside as i64)
            } else {
                toml::Value::Float(outside)
            };
            let table = toml::Table::from_iter([(p.name.clone(), value.clone())]);
            let mut e = (m.validate)(table.clone())
                .expect_err(&format!("{what} = {value} refused"))
                .to_string();
            if e.contains("unknown parameter") && m.name == "pathtrace" {
                // Render's own parameters are read by `render`, not by the method's solver.
                use radlab_method::MethodParams;
                e = radlab_pathtrace::RenderParams::from_table(table)
                    .expect_err(&format!("{what} = {value} refused by render"))
                    .to_string();
            }
            assert!(
                e.contains(&format!("'{}'", p.name)) && e.contains(&range.phrase(whole)),
                "{what} = {value}: {e}"
            );
        }
    }
}

#[test]
fn dates_are_found() {
    assert!(holds_a_date("the quickstart of 2026-12-02, later"));
    assert!(!holds_a_date("1e-4, 1..=16, 100000"));
}
