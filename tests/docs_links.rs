//! Every relative link in README.md and docs/ resolves: `[text](path)` names a file or folder
//! that exists (relative to the Markdown file), and `[text](path#anchor)` or `[text](#anchor)`
//! names a heading of the target Markdown file by its GitHub slug (lowercase; punctuation but
//! `-` and `_` removed; spaces to `-`; a repeated slug gets `-1`, `-2`, ...) or an explicit
//! `<a name="...">` / `id="..."` anchor. Links to other sites (`http:`, `https:`, `mailto:`),
//! links inside fenced code blocks and inline code are not checked. A failure lists every
//! broken link as `file:line: target (reason)`.

use std::collections::{HashMap, HashSet};
use std::path::{Component, Path, PathBuf};

use crate::common;

#[test]
fn every_relative_link_in_readme_and_docs_resolves() {
    let root = common::repo("");
    let mut files = vec![root.join("README.md")];
    markdown_files(&root.join("docs"), &mut files);
    files.sort();
    let mut checker = LinkChecker::new(&root);
    for file in &files {
        checker.check_file(file);
    }
    assert!(
        checker.checked > 100,
        "only {} relative links found in README.md and docs/: is the scan broken?",
        checker.checked
    );
    assert!(
        checker.broken.is_empty(),
        "{} of {} relative links in README.md and docs/ do not resolve:\n{}",
        checker.broken.len(),
        checker.checked,
        checker.broken.join("\n")
    );
}

/// The check itself: a missing file, a missing anchor (in another file and in the same one)
/// and a link to a missing file inside a fenced block or inline code, beside links that
/// resolve (headings with code, punctuation and a repeat; an explicit anchor; a folder).
#[test]
fn the_link_check_reports_missing_files_and_anchors_by_file_and_line() {
    let dir = std::env::temp_dir().join(format!("dormant-docs-links-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("docs/sub")).unwrap();
    std::fs::write(
        dir.join("docs/target.md"),
        "# Motion blur (`--shutter`)\n\n## 2026-12-02: n ≥ σ, and 8-wide nodes\n\n\
         ## Notes\n\n## Notes\n\n<a name=\"kept\"></a>\n\n```sh\n# not a heading\n```\n",
    )
    .unwrap();
    let text = "# Top\n\
        [ok](target.md#motion-blur---shutter) [ok](target.md#2026-12-02-n--σ-and-8-wide-nodes)\n\
        [ok](target.md#notes-1) [ok](target.md#kept) [ok](sub/) [ok](#top) [web](https://example.com/x)\n\
        [missing file](nowhere.md)\n\
        [missing anchor](target.md#not-a-heading)\n\
        `[in code](nowhere.md)` and [missing here](#nothing)\n\
        ```\n[fenced](nowhere.md)\n```\n";
    std::fs::write(dir.join("docs/index.md"), text).unwrap();
    let mut checker = LinkChecker::new(&dir);
    checker.check_file(&dir.join("docs/index.md"));
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(checker.checked, 9);
    assert_eq!(
        checker.broken,
        [
            "docs/index.md:4: nowhere.md (no such file: docs/nowhere.md)",
            "docs/index.md:5: target.md#not-a-heading (no heading or anchor `not-a-heading` in docs/target.md)",
            "docs/index.md:6: #nothing (no heading or anchor `nothing` in docs/index.md)",
        ]
    );
}

struct LinkChecker {
    root: PathBuf,
    /// Each Markdown file's anchors, read once.
    anchors: HashMap<PathBuf, HashSet<String>>,
    checked: usize,
    broken: Vec<String>,
}

impl LinkChecker {
    fn new(root: &Path) -> Self {
        LinkChecker { root: root.to_path_buf(), anchors: HashMap::new(), checked: 0, broken: Vec::new() }
    }

    fn check_file(&mut self, file: &Path) {
        let text = std::fs::read_to_string(file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        let shown = self.shown(file);
        for (line_no, line) in prose_lines(&text) {
            for target in link_targets(line) {
                if let Some(reason) = self.broken_reason(file, &target) {
                    self.broken.push(format!("{shown}:{line_no}: {target} ({reason})"));
                }
                self.checked += 1;
            }
        }
    }

    /// Why `target`, linked from `file`, does not resolve; `None` when it does.
    fn broken_reason(&mut self, file: &Path, target: &str) -> Option<String> {
        let (path, anchor) = match target.split_once('#') {
            Some((path, anchor)) => (path, Some(percent_decoded(anchor))),
            None => (target, None),
        };
        let path = percent_decoded(path.split('?').next().unwrap_or(""));
        let resolved = if path.is_empty() {
            file.to_path_buf()
        } else if let Some(from_root) = path.strip_prefix('/') {
            normalized(&self.root.join(from_root))
        } else {
            normalized(&file.parent().expect("a file's folder").join(&path))
        };
        if !resolved.exists() {
            return Some(format!("no such file: {}", self.shown(&resolved)));
        }
        let anchor = anchor.filter(|a| !a.is_empty())?;
        if !resolved.is_file() || resolved.extension().is_none_or(|e| e != "md") {
            return None; // GitHub's line anchors (`#L10`) and the like: not checked.
        }
        let anchors = self.anchors.entry(resolved.clone()).or_insert_with(|| {
            let text = std::fs::read_to_string(&resolved).unwrap_or_default();
            markdown_anchors(&text)
        });
        if anchors.contains(&anchor) {
            None
        } else {
            Some(format!("no heading or anchor `{anchor}` in {}", self.shown(&resolved)))
        }
    }

    /// `path` relative to the repository root, with `/` separators.
    fn shown(&self, path: &Path) -> String {
        let relative = path.strip_prefix(&self.root).unwrap_or(path);
        relative.components().map(|c| c.as_os_str().to_string_lossy()).collect::<Vec<_>>().join("/")
    }
}

/// Every `.md` file under `dir`, recursively.
fn markdown_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let entries = std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    for entry in entries {
        let path = entry.unwrap().path();
        if path.is_dir() {
            markdown_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "md") {
            out.push(path);
        }
    }
}

/// The lines outside fenced code blocks (``` or ~~~, at most three spaces in), numbered from 1.
fn prose_lines(text: &str) -> Vec<(usize, &str)> {
    let mut lines = Vec::new();
    let mut fence: Option<(char, usize)> = None;
    for (i, line) in text.lines().enumerate() {
        let indent = line.len() - line.trim_start_matches(' ').len();
        let rest = &line[indent..];
        let marker = rest.chars().next().filter(|&c| indent <= 3 && (c == '`' || c == '~'));
        let run = marker.map_or(0, |c| rest.chars().take_while(|&d| d == c).count());
        match (fence, marker) {
            (None, Some(c)) if run >= 3 => fence = Some((c, run)),
            (Some((c, n)), Some(d)) if c == d && run >= n && rest[run..].trim().is_empty() => fence = None,
            (None, _) => lines.push((i + 1, line)),
            (Some(_), _) => {}
        }
    }
    lines
}

/// `line` with its inline code spans (a run of backticks up to the next run of the same
/// length) blanked out.
fn without_inline_code(line: &str) -> String {
    let chars: Vec<char> = line.chars().collect();
    let mut out = String::with_capacity(line.len());
    let mut i = 0;
    while i < chars.len() {
        if chars[i] != '`' {
            out.push(chars[i]);
            i += 1;
            continue;
        }
        let run = chars[i..].iter().take_while(|&&c| c == '`').count();
        let mut j = i + run;
        let mut close = None;
        while j < chars.len() {
            if chars[j] == '`' {
                let other = chars[j..].iter().take_while(|&&c| c == '`').count();
                if other == run {
                    close = Some(j + other);
                    break;
                }
                j += other;
            } else {
                j += 1;
            }
        }
        match close {
            Some(end) => {
                out.push(' ');
                i = end;
            }
            None => {
                out.extend(&chars[i..i + run]);
                i += run;
            }
        }
    }
    out
}

/// The relative targets of the inline links and images on `line` (`[text](target)`,
/// `![alt](target "title")`, `[text](<target>)`), outside inline code.
fn link_targets(line: &str) -> Vec<String> {
    let line = without_inline_code(line);
    let mut targets = Vec::new();
    let mut rest = line.as_str();
    while let Some(at) = rest.find("](") {
        let after = &rest[at + 2..];
        // The destination ends at the `)` that balances the opening one.
        let mut depth = 0usize;
        let mut end = after.len();
        for (k, c) in after.char_indices() {
            match c {
                '(' => depth += 1,
                ')' if depth == 0 => {
                    end = k;
                    break;
                }
                ')' => depth -= 1,
                _ => {}
            }
        }
        let inside = after[..end].trim();
        let target = match inside.strip_prefix('<') {
            Some(bracketed) => bracketed.split('>').next().unwrap_or(""),
            None => inside.split_whitespace().next().unwrap_or(""),
        };
        let external = ["http:", "https:", "mailto:", "ftp:"].iter().any(|s| target.starts_with(s));
        if !target.is_empty() && !external {
            targets.push(target.to_string());
        }
        rest = &after[end.min(after.len())..];
    }
    targets
}

/// The anchors a Markdown file offers: its headings' GitHub slugs, with `-1`, `-2`, ... on
/// repeats, and explicit `<a name="...">` / `id="..."` anchors.
fn markdown_anchors(text: &str) -> HashSet<String> {
    let mut anchors = HashSet::new();
    let mut occurrences: HashMap<String, usize> = HashMap::new();
    for (_, line) in prose_lines(text) {
        for key in ["name=\"", "id=\""] {
            let mut rest = line;
            while let Some(at) = rest.find(key) {
                let value = &rest[at + key.len()..];
                if let Some(end) = value.find('"') {
                    anchors.insert(value[..end].to_string());
                }
                rest = value;
            }
        }
        if let Some(heading) = atx_heading(line) {
            // As github-slugger: a repeat gets the first free `-N`.
            let base = slug(heading);
            let mut candidate = base.clone();
            while occurrences.contains_key(&candidate) {
                let n = occurrences.get_mut(&base).expect("the base slug is recorded");
                *n += 1;
                candidate = format!("{base}-{n}");
            }
            occurrences.insert(candidate.clone(), 0);
            anchors.insert(candidate);
        }
    }
    anchors
}

/// The text of an ATX heading (`## Title ##`), or `None`.
fn atx_heading(line: &str) -> Option<&str> {
    let indent = line.len() - line.trim_start_matches(' ').len();
    if indent > 3 {
        return None;
    }
    let rest = &line[indent..];
    let level = rest.chars().take_while(|&c| c == '#').count();
    if !(1..=6).contains(&level) {
        return None;
    }
    let text = &rest[level..];
    if !text.is_empty() && !text.starts_with([' ', '\t']) {
        return None;
    }
    let text = text.trim();
    // A closing run of `#` preceded by a space is not part of the heading.
    let trimmed = text.trim_end_matches('#');
    Some(if trimmed.len() < text.len() && (trimmed.is_empty() || trimmed.ends_with(' ')) {
        trimmed.trim_end()
    } else {
        text
    })
}

/// GitHub's anchor for a heading: the rendered text (links as their text, no code or emphasis
/// markers) lowercased, every character but letters, digits, `-`, `_` and spaces removed,
/// and each space turned into `-`.
fn slug(heading: &str) -> String {
    let mut rendered = String::new();
    let mut rest = heading;
    // `[text](target)` renders as its text.
    while let Some(open) = rest.find('[') {
        let Some(close) = rest[open..].find("](").map(|c| open + c) else { break };
        let Some(end) = rest[close..].find(')').map(|e| close + e) else { break };
        rendered.push_str(&rest[..open]);
        rendered.push_str(&rest[open + 1..close]);
        rest = &rest[end + 1..];
    }
    rendered.push_str(rest);
    rendered
        .chars()
        .filter(|&c| c.is_alphanumeric() || c == '-' || c == '_' || c == ' ')
        .flat_map(char::to_lowercase)
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

/// `%XX` escapes decoded (as UTF-8); anything else kept.
fn percent_decoded(s: &str) -> String {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = bytes.get(i + 1..i + 3).and_then(|h| std::str::from_utf8(h).ok());
        match (bytes[i], hex.and_then(|h| u8::from_str_radix(h, 16).ok())) {
            (b'%', Some(byte)) => {
                out.push(byte);
                i += 3;
            }
            (byte, _) => {
                out.push(byte);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// `path` with `.` and `..` components resolved lexically (as a browser resolves a link).
fn normalized(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for component in path.components() {
        match component {
            Component::CurDir => {}
            Component::ParentDir => {
                out.pop();
            }
            other => out.push(other),
        }
    }
    out
}
