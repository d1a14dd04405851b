//! Every `hce` command the docs show names a subcommand and options the binary has: the code
//! blocks of README.md, BENCHMARKS.md, samples/README.md, web/README.md and docs/ are read, each
//! `hce SUBCOMMAND ...` found in them (also inside a hyperfine or shell line), and every option
//! checked against `hce SUBCOMMAND --help`. A renamed flag then fails here, not in a reader's
//! terminal.

mod common;

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The Markdown files whose commands are checked.
fn documents() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut files: Vec<PathBuf> = ["README.md", "BENCHMARKS.md", "samples/README.md"]
        .iter()
        .map(|f| root.join(f))
        .collect();
    files.push(root.join("web/README.md"));
    if let Ok(dir) = std::fs::read_dir(root.join("docs")) {
        let mut docs: Vec<PathBuf> = dir
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|e| e == "md"))
            .collect();
        docs.sort();
        files.extend(docs);
    }
    files
}

/// The lines of a Markdown text that are code: inside ``` fences or indented by four spaces
/// (outside lists' continuation lines, which a blank line precedes), with backslash
/// continuations joined.
fn code_lines(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut fenced = false;
    let mut pending: Option<(usize, String)> = None;
    for (i, line) in text.lines().enumerate() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        let code = if fenced {
            Some(line)
        } else {
            line.strip_prefix("    ")
        };
        let Some(code) = code else {
            if let Some(p) = pending.take() {
                out.push(p);
            }
            continue;
        };
        let (start, mut joined) = pending.take().unwrap_or((i + 1, String::new()));
        joined.push_str(code.trim());
        if let Some(stripped) = joined.strip_suffix('\\') {
            pending = Some((start, format!("{} ", stripped.trim_end())));
        } else {
            out.push((start, joined));
        }
    }
    out.extend(pending);
    out
}

/// Each `hce SUB ARGS` in a code line: the subcommand and its option names (`--name` without
/// `=value`, and short options), up to the end of that shell command (a quote, pipe,
/// semicolon, `&&`, redirection or comment).
fn hce_commands(line: &str) -> Vec<(String, Vec<String>)> {
    let mut out = Vec::new();
    // A shell comment is prose.
    let words: Vec<&str> = line
        .split_whitespace()
        .take_while(|w| !w.starts_with('#'))
        .collect();
    for (i, w) in words.iter().enumerate() {
        // `hce`, `target/release/hce`, or `'hce` opening a hyperfine argument.
        let bare = w.trim_start_matches(['\'', '"', '(']);
        // A path given as an option's value (`--hce target/release/hce`) is not a command.
        let is_value = i > 0 && {
            let p = words[i - 1].as_bytes();
            p.starts_with(b"--") || (p.len() == 2 && p[0] == b'-' && p[1].is_ascii_alphabetic())
        };
        if !(bare == "hce" || bare.ends_with("/hce")) || is_value || i + 1 >= words.len() {
            continue;
        }
        let sub = words[i + 1];
        if !sub.starts_with(|c: char| c.is_ascii_lowercase())
            || !sub.chars().all(|c| c.is_ascii_lowercase() || c == '-')
        {
            continue;
        }
        let mut options = Vec::new();
        for arg in &words[i + 2..] {
            if arg.starts_with('#') || ["|", ";", "&&", ">", "2>", ">>"].contains(arg) {
                break;
            }
            let ends = arg.ends_with(['\'', ';']);
            let arg = arg.trim_end_matches(['\'', ';']);
            if let Some(name) = arg.strip_prefix("--") {
                let name = name.split('=').next().unwrap_or(name);
                if !name.is_empty() {
                    options.push(format!("--{name}"));
                }
            } else if arg.len() == 2 && arg.starts_with('-') && arg != "--" {
                options.push(arg.to_string());
            }
            if ends {
                break;
            }
        }
        out.push((sub.to_string(), options));
    }
    out
}

/// The options `hce SUB --help` lists (long and short), or `None` if there is no such
/// subcommand.
fn options_of(sub: &str) -> Option<BTreeSet<String>> {
    let (code, stdout, _) = common::hce(&[sub, "--help"]);
    if code != 0 {
        return None;
    }
    let mut options = BTreeSet::new();
    for w in stdout.split(|c: char| c.is_whitespace() || c == ',' || c == '[' || c == ']') {
        let w = w.split('=').next().unwrap_or(w);
        let w = w.split('<').next().unwrap_or(w);
        if w.starts_with('-') && w.len() >= 2 && w.chars().nth(1) != Some(' ') {
            options.insert(w.to_string());
        }
    }
    Some(options)
}

#[test]
fn every_documented_hce_command_names_options_the_binary_has() {
    let mut help: BTreeMap<String, Option<BTreeSet<String>>> = BTreeMap::new();
    let mut problems = Vec::new();
    let mut checked = 0;
    for doc in documents() {
        let text = std::fs::read_to_string(&doc).unwrap_or_else(|e| panic!("{doc:?}: {e}"));
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let name = doc
            .strip_prefix(&root)
            .unwrap_or(&doc)
            .display()
            .to_string();
        for (line_no, line) in code_lines(&text) {
            for (sub, options) in hce_commands(&line) {
                checked += 1;
                let known = help.entry(sub.clone()).or_insert_with(|| options_of(&sub));
                let Some(known) = known else {
                    problems.push(format!("{name}:{line_no}: no subcommand `hce {sub}`"));
                    continue;
                };
                for o in options {
                    if !known.contains(&o) {
                        problems.push(format!("{name}:{line_no}: `hce {sub}` has no option {o}"));
                    }
                }
            }
        }
    }
    // The docs show several dozen commands; finding few means the scan broke, not the docs.
    assert!(
        checked >= 40,
        "only {checked} hce commands found in the docs"
    );
    assert!(problems.is_empty(), "{problems:#?}");
}

#[test]
fn the_scan_reads_continuations_quotes_and_comments() {
    let text =
        "text\n\n    hce bake a.glb -o b.glb \\\n        --creases auto # why hce viewer\n\n\
                ```\nhyperfine 'osd_loop x 3 -' 'hce subdivide x --level 3 -o y.glb'\n\
                hce-batch m.toml --hce target/release/hce --workers 2\n```\n";
    let lines = code_lines(text);
    assert_eq!(lines.len(), 3, "{lines:?}");
    assert!(hce_commands(&lines[2].1).is_empty(), "{lines:?}");
    assert_eq!(
        hce_commands(&lines[0].1),
        [(
            "bake".to_string(),
            vec!["-o".to_string(), "--creases".to_string()]
        )]
    );
    assert_eq!(
        hce_commands(&lines[1].1),
        [(
            "subdivide".to_string(),
            vec!["--level".to_string(), "-o".to_string()]
        )]
    );
    let known = options_of("bake").expect("hce bake exists");
    assert!(
        known.contains("--creases") && known.contains("-o"),
        "{known:?}"
    );
    assert!(!known.contains("--no-such-option"));
    assert!(options_of("no-such-subcommand").is_none());
}
