//! The repository's documentation stays true to the repository:
//!
//! - every figure the README and the docs quote from a results page is on that page (a
//!   paragraph after `<!-- figures: docs/results/PAGE.md -->` quotes PAGE; each of its numbers
//!   must appear there);
//! - a paragraph that quotes a measured figure has such a marker (`measured`, below, says what
//!   reads as measured), so that no figure escapes the first check;
//! - every link of a page points to a file;
//! - `docs/design.md` names every source file of the library, the Python package and the path
//!   tracer, read from the tree when the test runs;
//! - `docs/` stays under 15 MB: the files git tracks there and the files present that git does
//!   not ignore (the run folders the pages' commands make are ignored, `.gitignore`).
//!
//! These read the repository, not the crate: from a `.crate` (no `docs/`) they pass without
//! checking anything, and say so.

use std::collections::BTreeSet;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The repository's root, or `None` outside a clone (a packaged crate has no `docs/`).
fn repo() -> Option<PathBuf> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    if root.join("docs").join("design.md").is_file() {
        Some(root)
    } else {
        eprintln!("no docs/ beside the crate (a packaged crate): nothing to check");
        None
    }
}

fn read(path: &Path) -> String {
    fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The numbers in `text`, commas between digit groups removed (`49,152` is `49152`). With
/// `bare`, a number glued to a letter before it (`f15`, the `48` of `64x48`) is left out: it
/// is a name, not a figure.
fn numbers(text: &str, bare: bool) -> Vec<String> {
    let c: Vec<char> = text.chars().collect();
    number_spans(&c)
        .into_iter()
        .filter(|(start, _, _)| {
            let glued = *start > 0 && (c[start - 1].is_alphabetic() || c[start - 1] == '_');
            !(bare && glued)
        })
        .map(|(_, _, n)| n)
        .collect()
}

/// Every number of `c`: where it starts and ends, and its digits (thousands' commas out, a
/// fraction and an exponent kept).
fn number_spans(c: &[char]) -> Vec<(usize, usize, String)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < c.len() {
        let starts =
            c[i].is_ascii_digit() && (i == 0 || !(c[i - 1].is_ascii_digit() || c[i - 1] == '.'));
        if !starts {
            i += 1;
            continue;
        }
        let start = i;
        let mut s = String::new();
        let digits = |i: &mut usize, s: &mut String| {
            while *i < c.len() && c[*i].is_ascii_digit() {
                s.push(c[*i]);
                *i += 1;
            }
        };
        digits(&mut i, &mut s);
        // Thousands: a comma and exactly three digits.
        while i + 3 < c.len()
            && c[i] == ','
            && c[i + 1..i + 4].iter().all(char::is_ascii_digit)
            && c.get(i + 4).is_none_or(|d| !d.is_ascii_digit())
        {
            s.extend(&c[i + 1..i + 4]);
            i += 4;
        }
        if i + 1 < c.len() && c[i] == '.' && c[i + 1].is_ascii_digit() {
            s.push('.');
            i += 1;
            digits(&mut i, &mut s);
        }
        if i + 1 < c.len() && c[i] == 'e' {
            let sign = matches!(c[i + 1], '-' | '+');
            let at = i + 1 + usize::from(sign);
            if at < c.len() && c[at].is_ascii_digit() {
                s.extend(&c[i..at]);
                i = at;
                digits(&mut i, &mut s);
            }
        }
        out.push((start, i, s));
    }
    out
}

/// Whether the quoted figure `quoted` is one of the page's numbers: the same digits, or a page
/// number rounded to the quoted figure's significant digits (`2.6e-8` quotes `2.63e-08`). A
/// whole number (a count) must be on the page as it is.
fn on_page(quoted: &str, page: &[String]) -> bool {
    if page.iter().any(|p| p == quoted) {
        return true;
    }
    let (Ok(q), true) = (quoted.parse::<f64>(), quoted.contains(['.', 'e'])) else {
        return false;
    };
    let mantissa = quoted.split('e').next().unwrap_or("");
    let digits = mantissa
        .chars()
        .filter(char::is_ascii_digit)
        .skip_while(|d| *d == '0')
        .count();
    let Ok(digits) = i32::try_from(digits.max(1)) else {
        return false;
    };
    page.iter().filter_map(|p| p.parse::<f64>().ok()).any(|p| {
        if p == 0.0 || q == 0.0 {
            return p == q;
        }
        let scale = 10f64.powi(digits - 1 - p.abs().log10().floor() as i32);
        ((p * scale).round() / scale - q).abs() <= 1e-9 * q.abs()
    })
}

/// `text` without inline code (commands and names, not figures) and link targets.
fn prose(text: &str) -> String {
    let mut out = String::new();
    let mut code = false;
    let mut rest = text;
    while let Some(ch) = rest.chars().next() {
        if ch == '`' {
            code = !code;
        } else if !code && rest.starts_with("](") {
            let end = rest.find(')').unwrap_or(rest.len() - 1);
            out.push(']');
            rest = &rest[end + 1..];
            continue;
        } else if !code {
            out.push(ch);
        }
        rest = &rest[ch.len_utf8()..];
    }
    out
}

/// The markdown files whose figures are checked: the README and `docs/*.md`.
fn quoting_files(root: &Path) -> Vec<PathBuf> {
    let mut files = vec![root.join("README.md")];
    let mut docs: Vec<PathBuf> = fs::read_dir(root.join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "md"))
        .collect();
    docs.sort();
    files.extend(docs);
    files
}

#[test]
fn quoted_figures_match_their_pages() {
    let Some(root) = repo() else { return };
    let marker = "<!-- figures: ";
    let mut checked = 0;
    let mut wrong = Vec::new();
    for file in quoting_files(&root) {
        let text = read(&file);
        let lines: Vec<&str> = text.lines().collect();
        for (at, line) in lines.iter().enumerate() {
            let Some(rest) = line.trim().strip_prefix(marker) else {
                continue;
            };
            let page_name = rest.trim_end_matches("-->").trim();
            let page_path = root.join(page_name);
            assert!(
                page_path.is_file(),
                "{}: the marker names {page_name}, which is not a file",
                file.display()
            );
            let page = numbers(&read(&page_path), false);
            // The paragraph: the lines up to the next blank line.
            let paragraph: Vec<&str> = lines[at + 1..]
                .iter()
                .take_while(|l| !l.trim().is_empty())
                .copied()
                .collect();
            assert!(
                !paragraph.is_empty(),
                "{}: a figures marker before nothing",
                file.display()
            );
            for n in numbers(&prose(&paragraph.join("\n")), true) {
                checked += 1;
                if !on_page(&n, &page) && !PAPER.contains(&n.as_str()) {
                    wrong.push(format!(
                        "{} (line {}): {n} is not on {page_name}",
                        file.display(),
                        at + 2
                    ));
                }
            }
        }
    }
    assert!(
        checked > 0,
        "no figures marked: the README quotes results pages"
    );
    assert!(
        wrong.is_empty(),
        "figures that are not on the page they quote:\n{}",
        wrong.join("\n")
    );
}

/// The docs pages that are results pages themselves, written whole by a command (their
/// figures are that command's): their paragraphs need no marker.
const GENERATED: &[&str] = &["docs/estimators.md"];

/// Figures that read as measured but are settings or facts of the code, by file: the
/// figure as `measured` prints it.
const CONSTANTS: &[(&str, &str)] = &[
    // The margin of the sphere about a rotated box, a setting of the renderer.
    ("docs/renderer.md", "0.1 %"),
    // The sleeping objectives of the Ray test and study: settings, not timings.
    ("docs/scale-out.md", "0.2 s"),
    ("docs/scale-out.md", "0.1 s"),
];

/// The paper's figures (its Table 1's parameter and image MSEs per task, and TEXTURE's goal),
/// which every paragraph may quote, marked or not: targets, not measurements of this
/// repository.
const PAPER: &[&str] = &[
    "4.18e-7", "4.92e-6", "1.81e-3", "1.74e-5", "3.29e-3", "9.76e-5", "8.71e-4", "3.81e-3",
    "4.19e-1", "2.34e-4", "1.89e-5", "5.07e-5", "2.8e-3",
];

/// Units after a number with a fractional part that make it a measurement: times and sizes.
const UNITS: &[&str] = &[
    "s", "ms", "us", "µs", "μs", "ns", "min", "h", "GB", "MB", "kB", "KB",
];

/// Words after `N times` (or `Nx`) that make it a measured ratio.
const COMPARED: &[&str] = &[
    "faster", "slower", "fewer", "more", "less", "cheaper", "lower", "higher", "smaller", "larger",
    "below", "above",
];

/// The figures of `text` (inline code and link targets already out: `prose`) that read as
/// measured: a number with a fractional part followed by a unit of time or size (`1.61 s`,
/// `0.8 MB`) or by `%` (`0.7 %`); a ratio glued to `x` (`0.54x`, `27x`); scientific notation
/// with a fractional mantissa (`2.79e-2`: a setting is written `1e-3`); a number followed by
/// `times` or `x` and a comparison (`40 times smaller`). Settings are written round, results
/// are not: the rule leaves out `sigma0 = 0.5`, `a 90 s cap`, `1e-8` and `5 %` (a tolerance),
/// and `CONSTANTS` lists what it still takes for a measurement.
fn measured(text: &str) -> Vec<String> {
    let c: Vec<char> = text.chars().collect();
    let word = |from: usize| -> (String, usize) {
        let mut i = from;
        while i < c.len() && c[i] == ' ' {
            i += 1;
        }
        let start = i;
        while i < c.len() && (c[i].is_alphabetic() || c[i] == '%') {
            i += 1;
            if c[i - 1] == '%' {
                break;
            }
        }
        if c.get(i).is_some_and(|d| d.is_alphanumeric()) {
            return (String::new(), from); // `s2`: a name, not a unit
        }
        (c[start..i].iter().collect(), i)
    };
    let mut out = Vec::new();
    for (start, end, n) in number_spans(&c) {
        let mantissa = n.split('e').next().unwrap_or("");
        let fraction = mantissa.contains('.');
        let (unit, after) = word(end);
        let glued_x = c.get(end).is_some_and(|x| matches!(x, 'x' | '×'))
            && c.get(end + 1).is_none_or(|d| !d.is_alphanumeric());
        let (than, past) = word(after);
        let upto = if glued_x {
            Some(end + 1)
        } else if matches!(unit.as_str(), "times" | "x" | "×") && COMPARED.contains(&than.as_str())
        {
            Some(past)
        } else if fraction && (UNITS.contains(&unit.as_str()) || unit == "%") {
            Some(after)
        } else if fraction && n.contains('e') {
            Some(end)
        } else {
            None
        };
        if let Some(upto) = upto {
            out.push(c[start..upto].iter().collect());
        }
    }
    out
}

/// Every paragraph of the README and `docs/*.md` (but the `GENERATED` pages) that quotes a
/// figure `measured` finds follows a `<!-- figures: PAGE -->` marker, whose page the first
/// test then holds it to; the paper's figures (`PAPER`) and the settings in `CONSTANTS` need
/// none. Inline code and fenced blocks (commands, code, a program's sample output) are not
/// prose here (`prose`).
#[test]
fn measured_figures_name_their_page() {
    let Some(root) = repo() else { return };
    let mut unmarked = Vec::new();
    for file in quoting_files(&root) {
        let name = file
            .strip_prefix(&root)
            .unwrap()
            .to_string_lossy()
            .replace('\\', "/");
        if GENERATED.contains(&name.as_str()) {
            continue;
        }
        let text = read(&file);
        let mut marked = false;
        let mut paragraph: Vec<&str> = Vec::new();
        let mut first = 0;
        for (at, line) in text.lines().chain([""]).enumerate() {
            if !line.trim().is_empty() && !line.trim().starts_with("<!-- figures: ") {
                if paragraph.is_empty() {
                    first = at + 1;
                }
                paragraph.push(line);
                continue;
            }
            if !marked {
                for figure in measured(&prose(&paragraph.join("\n"))) {
                    if !PAPER.contains(&figure.as_str())
                        && !CONSTANTS.contains(&(name.as_str(), figure.as_str()))
                    {
                        unmarked.push(format!("{name} (line {first}): {figure}"));
                    }
                }
            }
            marked = line.trim().starts_with("<!-- figures: ");
            paragraph.clear();
        }
    }
    assert!(
        unmarked.is_empty(),
        "measured figures in paragraphs without a `<!-- figures: PAGE -->` marker (tie them to \
         their results page, or link the page instead; a setting goes in CONSTANTS):\n{}",
        unmarked.join("\n")
    );
}

/// Relative link targets of a markdown text (no URLs, no anchors within the page).
fn links(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    for (i, _) in text.match_indices("](") {
        let rest = &text[i + 2..];
        let Some(end) = rest.find(')') else { continue };
        let target = rest[..end].split('#').next().unwrap_or("").trim();
        if !target.is_empty()
            && !target.contains("://")
            && !target.starts_with("mailto:")
            && !target.contains(' ')
        {
            out.push(target.to_string());
        }
    }
    out
}

#[test]
fn every_link_of_a_page_points_to_a_file() {
    let Some(root) = repo() else { return };
    let mut pages = quoting_files(&root);
    let mut results: Vec<PathBuf> = fs::read_dir(root.join("docs/results"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "md"))
        .collect();
    results.sort();
    pages.extend(results);
    let mut seen = BTreeSet::new();
    let mut broken = Vec::new();
    while let Some(page) = pages.pop() {
        if !seen.insert(page.clone()) {
            continue;
        }
        for target in links(&read(&page)) {
            let path = page.parent().unwrap().join(&target);
            if !path.exists() {
                broken.push(format!(
                    "{}: {target}",
                    page.strip_prefix(&root).unwrap().display()
                ));
            } else if path.extension().is_some_and(|x| x == "md") {
                pages.push(path.canonicalize().unwrap());
            }
        }
    }
    assert!(
        broken.is_empty(),
        "links to files that are not there:\n{}",
        broken.join("\n")
    );
}

/// Every file under `dir`, in its folders.
fn walk(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut todo = vec![dir.to_path_buf()];
    while let Some(d) = todo.pop() {
        for e in fs::read_dir(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display())) {
            let p = e.unwrap().path();
            if p.is_dir() {
                todo.push(p);
            } else {
                out.push(p);
            }
        }
    }
    out
}

/// Every file under `dir` ending in one of `exts`, as paths relative to `dir`.
fn sources(dir: &Path, exts: &[&str]) -> Vec<String> {
    let mut out: Vec<String> = walk(dir)
        .into_iter()
        .filter(|p| {
            p.extension()
                .and_then(|x| x.to_str())
                .is_some_and(|x| exts.contains(&x))
        })
        .map(|p| {
            p.strip_prefix(dir)
                .unwrap()
                .to_string_lossy()
                .replace('\\', "/")
        })
        .collect();
    out.sort();
    out
}

/// The lines of `design.md`'s section headed `heading` (up to the next `## `).
fn section<'a>(design: &'a str, heading: &str) -> Vec<&'a str> {
    let mut lines = design.lines().skip_while(|l| l.trim() != heading);
    assert!(
        lines.next().is_some(),
        "docs/design.md has no section `{heading}`"
    );
    lines.take_while(|l| !l.starts_with("## ")).collect()
}

/// Whether the section names `rel` (`a/b/c.rs`): as `` `a/b/c.rs` ``, or on one line (a row of
/// its table) that names its folders as `` `a/` `` and `` `b/` `` and the file as `` `c.rs` ``.
fn on_the_map(lines: &[&str], rel: &str) -> bool {
    let whole = format!("`{rel}`");
    let parts: Vec<&str> = rel.split('/').collect();
    let (file, folders) = parts.split_last().unwrap();
    lines.iter().any(|l| {
        l.contains(&whole)
            || (l.contains(&format!("`{file}`"))
                && folders.iter().all(|d| l.contains(&format!("`{d}/`"))))
    })
}

#[test]
fn every_source_file_is_on_the_map() {
    let Some(root) = repo() else { return };
    let design = read(&root.join("docs/design.md"));
    let maps = [
        (
            "## The library, file by file",
            root.join("src"),
            "",
            &["rs"][..],
        ),
        (
            "## The Python package, file by file",
            root.join("python"),
            "src",
            &["rs"][..],
        ),
        (
            "## The Python package, file by file",
            root.join("python"),
            "plateau_free",
            &["py"][..],
        ),
        (
            "## The path tracer, file by file",
            root.join("examples/pathtracer/src"),
            "",
            &["rs"][..],
        ),
    ];
    let mut missing = Vec::new();
    for (heading, base, sub, exts) in maps {
        let lines = section(&design, heading);
        let files = sources(&base.join(sub), exts);
        assert!(
            !files.is_empty(),
            "{}: no sources",
            base.join(sub).display()
        );
        for file in files {
            let rel = if sub.is_empty() {
                file
            } else {
                format!("{sub}/{file}")
            };
            if !on_the_map(&lines, &rel) {
                missing.push(format!("{heading}: {rel}"));
            }
        }
    }
    assert!(
        missing.is_empty(),
        "source files docs/design.md does not name:\n{}",
        missing.join("\n")
    );
}

/// The size of `docs/` as a clone has it: the files git tracks there and the present files it
/// does not ignore (`git ls-files --cached --others --exclude-standard`). Without git, every
/// file under `docs/`.
fn docs_files(root: &Path) -> Vec<PathBuf> {
    let git = Command::new("git")
        .args([
            "ls-files",
            "-z",
            "--cached",
            "--others",
            "--exclude-standard",
            "--",
            "docs",
        ])
        .current_dir(root)
        .output();
    match git {
        Ok(out) if out.status.success() => out
            .stdout
            .split(|b| *b == 0)
            .filter(|s| !s.is_empty())
            .map(|s| root.join(String::from_utf8_lossy(s).as_ref()))
            .collect(),
        _ => walk(&root.join("docs")),
    }
}

#[test]
fn docs_stay_under_15_mb() {
    let Some(root) = repo() else { return };
    const LIMIT: u64 = 15_000_000;
    let mut sizes: Vec<(u64, PathBuf)> = docs_files(&root)
        .into_iter()
        .filter_map(|p| fs::metadata(&p).ok().map(|m| (m.len(), p)))
        .collect();
    let total: u64 = sizes.iter().map(|s| s.0).sum();
    sizes.sort();
    let largest: Vec<String> = sizes
        .iter()
        .rev()
        .take(5)
        .map(|(n, p)| format!("{} ({n} bytes)", p.strip_prefix(&root).unwrap().display()))
        .collect();
    assert!(
        total < LIMIT,
        "docs/ holds {total} bytes, over {LIMIT}: keep run folders out of git (docs/results.md); the largest: {}",
        largest.join(", ")
    );
}

/// A source file fits in a reader's head: none of the library, the tests, the bindings, the
/// path tracer, the studies or the scripts is over 700 lines.
#[test]
fn no_source_file_is_over_700_lines() {
    let Some(root) = repo() else { return };
    const MOST: usize = 700;
    let mut long = Vec::new();
    for dir in [
        "src", "tests", "benches", "examples", "python", "studies", "scripts",
    ] {
        let dir = root.join(dir);
        if !dir.is_dir() {
            continue;
        }
        for rel in sources(&dir, &["rs", "py", "pyi"]) {
            let lines = read(&dir.join(&rel)).lines().count();
            if lines > MOST {
                long.push(format!("{}/{rel} ({lines} lines)", dir.display()));
            }
        }
    }
    assert!(long.is_empty(), "over {MOST} lines: {}", long.join(", "));
}

#[test]
fn the_number_reader_reads_figures_as_pages_print_them() {
    assert_eq!(
        numbers("0.30 ms at n = 49,152; 1.81e-3 and 4.6e-6", true),
        ["0.30", "49152", "1.81e-3", "4.6e-6"]
    );
    assert_eq!(numbers("f15 at 64x48, N^1.02", true), ["64", "1.02"]);
    assert_eq!(numbers("64x48", false), ["64", "48"]);
    assert_eq!(numbers("1,2 and 3.", true), ["1", "2", "3"]);
    assert_eq!(
        prose("`--samples 32` and [page](results/fig1.md) 5"),
        " and [page] 5"
    );
    assert_eq!(
        measured("1.61 s, 0.7 %, 0.54x, 27x and 2.79e-2; 40 times smaller"),
        [
            "1.61 s",
            "0.7 %",
            "0.54x",
            "27x",
            "2.79e-2",
            "40 times smaller"
        ]
    );
    assert!(measured("sigma0 = 0.5, a 90 s cap, 1e-8, 5 %, 64x48, 0.7 x 0.6, 1.5 s2").is_empty());
}
