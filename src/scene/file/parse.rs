//! Reading a scene file: TOML text -> [`SceneDocument`] -> validation, with errors that
//! name the file, line and field.

use std::ops::Range;
use std::path::{Path, PathBuf};

use super::schema::SceneDocument;
use super::validate::{validate, Problem};
use super::SceneError;

/// A validated scene file: the parsed description plus where it came from. Plain data.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneFile {
    /// The file the description was read from (used in messages and to resolve asset paths).
    pub path: PathBuf,
    /// FNV-1a 64 hash of the file's bytes; trajectories record it.
    pub source_hash: u64,
    pub description: SceneDocument,
    source: String,
    /// Overrides `scene.assets` (from a command line).
    asset_override: Option<PathBuf>,
}

impl SceneFile {
    /// Reads, parses and validates a scene file.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, SceneError> {
        Self::load_with_assets(path, None)
    }

    /// Like [`Self::load`], resolving relative asset paths against `assets` (when given)
    /// instead of the scene's `scene.assets` directory.
    pub fn load_with_assets(path: impl AsRef<Path>, assets: Option<&Path>) -> Result<Self, SceneError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path)
            .map_err(|source| SceneError::Io { file: path.to_path_buf(), source })?;
        Self::parse_with_assets(path, text, assets)
    }

    /// Parses and validates scene text; `path` names it in messages and anchors relative
    /// asset paths.
    pub fn parse(path: impl AsRef<Path>, text: impl Into<String>) -> Result<Self, SceneError> {
        Self::parse_with_assets(path, text, None)
    }

    /// Like [`Self::parse`] with an asset directory override.
    pub fn parse_with_assets(
        path: impl AsRef<Path>,
        text: impl Into<String>,
        assets: Option<&Path>,
    ) -> Result<Self, SceneError> {
        let path = path.as_ref().to_path_buf();
        let source = text.into();
        let description: SceneDocument =
            toml::from_str(&source).map_err(|e| syntax_error(&path, &source, &e))?;
        let file = SceneFile {
            source_hash: fnv1a64(source.as_bytes()),
            path,
            description,
            source,
            asset_override: assets.map(Path::to_path_buf),
        };
        if let Some(problem) = validate(&file).into_iter().next() {
            return Err(file.invalid(problem));
        }
        Ok(file)
    }

    /// The directory asset paths are relative to.
    pub fn base_dir(&self) -> &Path {
        self.path.parent().unwrap_or_else(|| Path::new(""))
    }

    /// The directory relative asset paths resolve against: the override given when loading,
    /// else `scene.assets` (relative to the scene file), else the scene file's directory.
    pub fn asset_dir(&self) -> PathBuf {
        match (&self.asset_override, &self.description.scene.assets) {
            (Some(dir), _) => dir.clone(),
            (None, Some(dir)) => self.base_dir().join(dir),
            (None, None) => self.base_dir().to_path_buf(),
        }
    }

    /// Whether relative asset paths resolve against a directory given when loading.
    pub fn has_asset_override(&self) -> bool {
        self.asset_override.is_some()
    }

    /// An asset path from the file, resolved against [`Self::asset_dir`] (absolute paths are
    /// kept).
    pub fn resolve(&self, relative: &str) -> PathBuf {
        self.asset_dir().join(relative)
    }

    /// The scene text as read.
    pub fn source(&self) -> &str {
        &self.source
    }

    /// The 1-based line where the field at `path` (e.g. `spawners[1].count`) is written, if
    /// it is written at all.
    pub fn line_of(&self, path: &str) -> Option<usize> {
        let span = locate(&self.source, path)?;
        Some(line_of_offset(&self.source, span.start))
    }

    /// A [`SceneError::Invalid`] for `field`, with its line.
    pub fn error(&self, field: impl Into<String>, message: impl Into<String>) -> SceneError {
        let field = field.into();
        SceneError::Invalid {
            file: self.path.clone(),
            line: self.line_of(&field),
            field,
            message: message.into(),
        }
    }

    /// Scales every spawner's count so that they add up to `total` (at least one object per
    /// spawner, and no more waves than objects). `total` must be at least the number of
    /// spawners.
    pub fn with_total_count(mut self, total: u32) -> Result<Self, SceneError> {
        let spawners = &mut self.description.spawners;
        if spawners.is_empty() {
            return Err(self.error("spawners", "--count given but the scene has no spawners"));
        }
        if (total as usize) < spawners.len() {
            let n = spawners.len();
            return Err(
                self.error("spawners", format!("--count {total} is less than the number of spawners ({n})"))
            );
        }
        let old_total: u64 = spawners.iter().map(|s| s.count as u64).sum();
        let mut assigned = 0u64;
        let n = spawners.len();
        for (i, s) in spawners.iter_mut().enumerate() {
            let share = if i + 1 == n {
                total as u64 - assigned
            } else {
                (total as u64 * s.count as u64 / old_total).max(1)
            };
            let remaining_spawners = (n - i - 1) as u64;
            let share = share.min(total as u64 - assigned - remaining_spawners).max(1);
            s.count = share as u32;
            s.waves = s.waves.min(s.count);
            assigned += share;
        }
        debug_assert_eq!(assigned, total as u64);
        // The override changes what is simulated: fold it into the hash.
        self.source_hash = fnv1a64_extend(self.source_hash, &total.to_le_bytes());
        Ok(self)
    }

    fn invalid(&self, problem: Problem) -> SceneError {
        self.error(problem.field, problem.message)
    }
}

fn syntax_error(path: &Path, source: &str, e: &toml::de::Error) -> SceneError {
    let (line, column, field) = match e.span() {
        Some(span) => {
            let line = line_of_offset(source, span.start);
            let column = span.start - source[..span.start].rfind('\n').map_or(0, |i| i + 1) + 1;
            (line, column, field_at(source, span))
        }
        None => (1, 1, String::from("(document)")),
    };
    SceneError::Syntax {
        file: path.to_path_buf(),
        line,
        column,
        field,
        message: e.message().trim().to_string(),
    }
}

/// A readable name for what sits at `span`: the enclosing table header plus the key on that
/// line, e.g. `spawners.count`.
fn field_at(source: &str, span: Range<usize>) -> String {
    let start = span.start.min(source.len());
    let line_start = source[..start].rfind('\n').map_or(0, |i| i + 1);
    let line_end = source[start..].find('\n').map_or(source.len(), |i| start + i);
    let line = source[line_start..line_end].trim();
    let header = source[..line_start]
        .lines()
        .rev()
        .map(str::trim)
        .find(|l| l.starts_with('['))
        .map(|l| l.trim_matches(|c| c == '[' || c == ']').trim().to_string());
    if line.starts_with('[') {
        return line.trim_matches(|c| c == '[' || c == ']').trim().to_string();
    }
    let key = line.split('=').next().unwrap_or("").trim().trim_matches('"');
    match (header, key.is_empty()) {
        (Some(h), false) => format!("{h}.{key}"),
        (Some(h), true) => h,
        (None, false) => key.to_string(),
        (None, true) => String::from("(document)"),
    }
}

fn line_of_offset(source: &str, offset: usize) -> usize {
    source.as_bytes()[..offset.min(source.len())].iter().filter(|&&b| b == b'\n').count() + 1
}

/// Path segments of `a.b[2].c`.
enum Segment<'a> {
    Key(&'a str),
    Index(usize),
}

fn segments(path: &str) -> Vec<Segment<'_>> {
    let mut out = Vec::new();
    for part in path.split('.') {
        let (key, rest) = part.split_at(part.find('[').unwrap_or(part.len()));
        if !key.is_empty() {
            out.push(Segment::Key(key));
        }
        for index in rest.split('[').filter(|s| !s.is_empty()) {
            if let Ok(i) = index.trim_end_matches(']').parse() {
                out.push(Segment::Index(i));
            }
        }
    }
    out
}

/// The byte span of the deepest part of `path` that is written in `source`.
fn locate(source: &str, path: &str) -> Option<Range<usize>> {
    use toml_edit::{Item, Value};
    let doc = toml_edit::ImDocument::parse(source).ok()?;
    let mut best = None;
    enum Node<'a> {
        Item(&'a Item),
        Value(&'a Value),
        Table(&'a toml_edit::Table),
    }
    let mut node = Node::Table(doc.as_table());
    for seg in segments(path) {
        let next = match (&node, seg) {
            (Node::Table(t), Segment::Key(k)) => {
                if let Some((key, _)) = t.get_key_value(k) {
                    if let Some(s) = key.span() {
                        best = Some(s);
                    }
                }
                t.get(k).map(Node::Item)
            }
            (Node::Item(Item::Table(t)), Segment::Key(k)) => {
                if let Some((key, _)) = t.get_key_value(k) {
                    if let Some(s) = key.span() {
                        best = Some(s);
                    }
                }
                t.get(k).map(Node::Item)
            }
            (Node::Item(Item::Value(Value::InlineTable(t))), Segment::Key(k))
            | (Node::Value(Value::InlineTable(t)), Segment::Key(k)) => {
                if let Some((key, _)) = t.get_key_value(k) {
                    if let Some(s) = key.span() {
                        best = Some(s);
                    }
                }
                t.get(k).map(Node::Value)
            }
            (Node::Item(Item::ArrayOfTables(a)), Segment::Index(i)) => a.get(i).map(|t| {
                if let Some(s) = t.span() {
                    best = Some(s);
                }
                Node::Table(t)
            }),
            (Node::Item(Item::Value(Value::Array(a))), Segment::Index(i))
            | (Node::Value(Value::Array(a)), Segment::Index(i)) => a.get(i).map(|v| {
                if let Some(s) = v.span() {
                    best = Some(s);
                }
                Node::Value(v)
            }),
            _ => None,
        };
        match next {
            Some(n) => {
                if let Node::Item(Item::Value(v)) = &n {
                    if let Some(s) = v.span() {
                        best = Some(s);
                    }
                }
                node = n;
            }
            None => break,
        }
    }
    best
}

/// FNV-1a, 64 bit: a small stable hash for scene identity (not for security).
pub(crate) fn fnv1a64(bytes: &[u8]) -> u64 {
    fnv1a64_extend(0xcbf2_9ce4_8422_2325, bytes)
}

pub(crate) fn fnv1a64_extend(mut hash: u64, bytes: &[u8]) -> u64 {
    for &b in bytes {
        hash ^= b as u64;
        hash = hash.wrapping_mul(0x0100_0000_01b3);
    }
    hash
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn locate_finds_array_of_tables_fields() {
        let src = "[scene]\nname = \"x\"\n\n[[spawners]]\ncount = 1\n\n[[spawners]]\ncount = 0\n";
        let span = locate(src, "spawners[1].count").unwrap();
        assert_eq!(line_of_offset(src, span.start), 8);
        let span = locate(src, "scene.name").unwrap();
        assert_eq!(line_of_offset(src, span.start), 2);
    }

    #[test]
    fn locate_falls_back_to_the_deepest_written_part() {
        let src = "[scene]\nname = \"x\"\n";
        let span = locate(src, "scene.frames").unwrap();
        assert_eq!(line_of_offset(src, span.start), 1);
    }
}
