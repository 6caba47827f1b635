//! Scene loading errors: [`SpecErrorKind`], [`SpecError`] and the `SourceIndex` that maps
//! field paths to source positions.
//!
//! Every located error is `FILE:LINE:COLUMN: FIELD.PATH: message`, e.g.
//! `scenes/foo.toml:12:1: links[1].mass: must be > 0 (got -0.02)`; `SourceIndex` is built
//! from toml's span-preserving `DeTable` and also names the field of TOML syntax and serde
//! errors.

/// What kind of problem a [`SpecError::At`] reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SpecErrorKind {
    /// The text is not valid TOML.
    Syntax,
    /// A key the schema does not have (`deny_unknown_fields`).
    UnknownField,
    /// A required key is absent.
    MissingField,
    /// A value of the wrong type or shape (e.g. a string where a number is expected).
    WrongType,
    /// A well-typed value that is physically or logically invalid (NaN, m ≤ 0, ...).
    Invalid,
    /// A chain choice (`--base`/`--tip` of the command line) for a scene that names no URDF
    /// to choose it from: a mistake in the command line rather than in the file.
    ChainChoice,
}

/// Error from loading or validating a scene. Display format:
/// `FILE:LINE:COLUMN: FIELD.PATH: message`, e.g.
/// `scenes/foo.toml:12:1: links[1].mass: must be > 0 (got -0.02)`.
/// Lines and columns are 1-based; array indices in the field path are 0-based TOML indices
/// (`links[1]` is the second `[[links]]` table, i.e. DH link 2).
#[derive(Debug, thiserror::Error)]
pub enum SpecError {
    /// The file could not be read. The I/O error is part of the message, not a source: a
    /// build script that prints the error alone (`panic!("{e}")`) must say why.
    #[error("{file}: cannot read scene file: {cause}")]
    Io {
        /// The path as given.
        file: String,
        /// The underlying I/O error.
        cause: std::io::Error,
    },
    /// A located problem in the scene text.
    #[error("{file}:{line}:{column}: {path}: {message}")]
    At {
        /// Problem category.
        kind: SpecErrorKind,
        /// The origin (file name) given to the parser.
        file: String,
        /// 1-based line.
        line: usize,
        /// 1-based column (in characters).
        column: usize,
        /// Field path, e.g. `links[1].mass`, `base.rotation[0][2]`; `(document)` if unknown.
        path: String,
        /// What is wrong.
        message: String,
    },
    /// A located problem in a URDF file (boxed: it keeps the error small for the enums that
    /// carry a `SpecError`).
    #[error(transparent)]
    Urdf(Box<UrdfError>),
    /// A chain's base or tip names no link of the URDF. Who named it (a command line's
    /// `--base`/`--tip`, a scene's `base_link`/`tip_link`) is known only to the caller, which
    /// blames that flag or key; read on its own it is located at the URDF's `<robot>`.
    #[error(transparent)]
    UnknownLink(Box<UnknownLink>),
}

/// Which end of a chain a link name was given for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ChainEnd {
    /// The chain's base link (`--base`, `base_link`).
    Base,
    /// The chain's tip link (`--tip`, `tip_link`).
    Tip,
}

impl ChainEnd {
    /// The command-line flag that names this end (`--base`, `--tip`).
    pub fn flag(self) -> &'static str {
        match self {
            ChainEnd::Base => "--base",
            ChainEnd::Tip => "--tip",
        }
    }

    /// The scene key that names this end (`base_link`, `tip_link`).
    pub fn key(self) -> &'static str {
        match self {
            ChainEnd::Base => "base_link",
            ChainEnd::Tip => "tip_link",
        }
    }
}

impl std::fmt::Display for ChainEnd {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            ChainEnd::Base => "base",
            ChainEnd::Tip => "tip",
        })
    }
}

/// Chain ends that name no link of a URDF: `FILE:LINE:COLUMN: <robot> : base link "NAME" is
/// not a link of the robot (links: [...])`, at the URDF's `<robot>` element. Both ends are
/// checked before anything else in the file, so that a caller can blame a command line's
/// flag before a scene's key or the URDF itself.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "{file}:{line}:{column}: <robot> : {} (links: {links:?})",
    describe_ends(unknown)
)]
pub struct UnknownLink {
    /// The URDF file as named by the user or the scene.
    pub file: String,
    /// 1-based line of the `<robot>` element.
    pub line: usize,
    /// 1-based column of the `<robot>` element.
    pub column: usize,
    /// Each end whose name is no link, with that name (the base first).
    pub unknown: Vec<(ChainEnd, String)>,
    /// The robot's link names, in the file's order.
    pub links: Vec<String>,
}

fn describe_ends(unknown: &[(ChainEnd, String)]) -> String {
    let ends: Vec<String> = unknown
        .iter()
        .map(|(end, name)| format!("{end} link {name:?}"))
        .collect();
    match ends.len() {
        1 => format!("{} is not a link of the robot", ends[0]),
        _ => format!("{} are not links of the robot", ends.join(" and ")),
    }
}

/// A problem in a URDF file: `FILE:LINE:COLUMN: <ELEMENT> ATTRIBUTE: message`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{file}:{line}:{column}: <{element}> {attribute}: {message}")]
pub struct UrdfError {
    /// The URDF file as named by the user or the scene.
    pub file: String,
    /// 1-based line.
    pub line: usize,
    /// 1-based column.
    pub column: usize,
    /// The element (`joint`, `link`, `inertial`, `origin`, ...).
    pub element: String,
    /// The attribute or child element at fault (empty when the element as a whole is).
    pub attribute: String,
    /// What is wrong.
    pub message: String,
}

impl SpecError {
    /// The field path (`None` for I/O errors).
    pub fn path(&self) -> Option<&str> {
        match self {
            SpecError::At { path, .. } => Some(path),
            SpecError::Io { .. } | SpecError::Urdf(_) | SpecError::UnknownLink(_) => None,
        }
    }

    /// The 1-based line (`None` for I/O errors).
    pub fn line(&self) -> Option<usize> {
        match self {
            SpecError::At { line, .. } => Some(*line),
            SpecError::Urdf(e) => Some(e.line),
            SpecError::UnknownLink(e) => Some(e.line),
            SpecError::Io { .. } => None,
        }
    }

    /// The problem category (`None` for I/O errors).
    pub fn kind(&self) -> Option<SpecErrorKind> {
        match self {
            SpecError::At { kind, .. } => Some(*kind),
            SpecError::Io { .. } | SpecError::Urdf(_) | SpecError::UnknownLink(_) => None,
        }
    }
}

/// Maps field paths to source positions, built from toml's span-preserving parse tree.
pub(super) struct SourceIndex<'a> {
    /// Whether a parse tree was given (scenes built in code have none).
    tree: bool,
    text: &'a str,
    origin: &'a str,
    /// (path, position to report, covered span, value span) for every key and array element.
    entries: Vec<(
        String,
        usize,
        std::ops::Range<usize>,
        std::ops::Range<usize>,
    )>,
}

impl<'a> SourceIndex<'a> {
    pub(super) fn new(
        text: &'a str,
        origin: &'a str,
        root: Option<&toml::de::DeTable<'_>>,
    ) -> Self {
        let mut idx = SourceIndex {
            tree: root.is_some(),
            text,
            origin,
            entries: Vec::new(),
        };
        if let Some(t) = root {
            idx.walk_table(t, "");
        }
        idx
    }

    fn walk_table(&mut self, t: &toml::de::DeTable<'_>, prefix: &str) {
        for (k, v) in t.iter() {
            let path = if prefix.is_empty() {
                k.get_ref().to_string()
            } else {
                format!("{prefix}.{}", k.get_ref())
            };
            let ks = k.span();
            let vs = v.span();
            let cover = ks.start.min(vs.start)..ks.end.max(vs.end);
            self.entries.push((path.clone(), ks.start, cover, vs));
            self.walk_value(v.get_ref(), &path);
        }
    }

    fn walk_value(&mut self, v: &toml::de::DeValue<'_>, path: &str) {
        match v {
            toml::de::DeValue::Table(t) => self.walk_table(t, path),
            toml::de::DeValue::Array(a) => {
                for (i, e) in a.iter().enumerate() {
                    let p = format!("{path}[{i}]");
                    let s = e.span();
                    self.entries.push((p.clone(), s.start, s.clone(), s));
                    self.walk_value(e.get_ref(), &p);
                }
            }
            _ => {}
        }
    }

    /// Whether a scene text was parsed (a scene built in code has none).
    pub(super) fn parsed(&self) -> bool {
        self.tree
    }

    /// Whether the text gives `path` as a string (`"…"` or `'…'`); `None` for a scene built
    /// in code (no text).
    pub(super) fn is_string(&self, path: &str) -> Option<bool> {
        self.tree.then(|| {
            self.entries
                .iter()
                .find(|(p, ..)| p == path)
                .and_then(|(.., value)| self.text.get(value.clone()))
                .is_some_and(|v| v.starts_with(['"', '\'']))
        })
    }

    /// Whether the text gives `path`; `None` for a scene built in code (no text).
    pub(super) fn has(&self, path: &str) -> Option<bool> {
        self.tree
            .then(|| self.entries.iter().any(|(p, ..)| p == path))
    }

    /// A problem of `kind` at `path`.
    pub(super) fn at(&self, kind: SpecErrorKind, path: &str, message: String) -> SpecError {
        self.error(kind, self.offset_of(path), path, message)
    }

    /// A required key that is absent, reported at its table.
    pub(super) fn missing(&self, path: &str, message: String) -> SpecError {
        self.error(
            SpecErrorKind::MissingField,
            self.offset_of(path),
            path,
            message,
        )
    }

    /// The innermost path whose key or value covers byte `offset`.
    fn path_at(&self, offset: usize) -> Option<&str> {
        self.entries
            .iter()
            .filter(|(_, _, s, _)| s.start <= offset && offset < s.end.max(s.start + 1))
            .min_by_key(|(p, _, s, _)| (s.end - s.start, usize::MAX - p.len()))
            .map(|(p, _, _, _)| p.as_str())
    }

    /// Byte offset to report for `path`, falling back to its parents.
    fn offset_of(&self, path: &str) -> usize {
        let mut p = path;
        loop {
            if let Some((_, pos, _, _)) = self.entries.iter().find(|(q, _, _, _)| q == p) {
                return *pos;
            }
            match p.rfind(['.', '[']) {
                Some(i) => p = &p[..i],
                None => return 0,
            }
        }
    }

    fn line_col(&self, offset: usize) -> (usize, usize) {
        let mut off = offset.min(self.text.len());
        while !self.text.is_char_boundary(off) {
            off -= 1;
        }
        let before = &self.text[..off];
        let line = before.matches('\n').count() + 1;
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        let column = before[line_start..].chars().count() + 1;
        (line, column)
    }

    fn error(&self, kind: SpecErrorKind, offset: usize, path: &str, message: String) -> SpecError {
        let (line, column) = self.line_col(offset);
        SpecError::At {
            kind,
            file: self.origin.to_string(),
            line,
            column,
            path: if path.is_empty() {
                "(document)".to_string()
            } else {
                path.to_string()
            },
            message,
        }
    }

    /// A semantic error at `path`.
    pub(super) fn invalid(&self, path: &str, message: String) -> SpecError {
        self.error(SpecErrorKind::Invalid, self.offset_of(path), path, message)
    }

    /// Best-effort path for a position in text that may not parse: the last table header before
    /// the line plus the key on the line (`[[x]]` headers are counted to give `x[i]`).
    fn textual_path(&self, offset: usize) -> Option<String> {
        let off = offset.min(self.text.len());
        let line_start = self.text[..off].rfind('\n').map_or(0, |i| i + 1);
        let line_end = self.text[off..]
            .find('\n')
            .map_or(self.text.len(), |i| off + i);
        let line = self.text[line_start..line_end].trim();
        let key = match line.split_once('=') {
            Some((k, _)) if !line.starts_with('[') && !line.starts_with('#') => {
                let k = k.trim();
                let bare = !k.is_empty()
                    && k.chars()
                        .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-' || c == '.');
                bare.then(|| k.to_string())
            }
            _ => None,
        };
        let mut header: Option<String> = None;
        let mut counts: Vec<(String, usize)> = Vec::new();
        for l in self.text[..line_start]
            .lines()
            .chain(line.starts_with('[').then_some(line))
        {
            let l = l.trim();
            if let Some(h) = l.strip_prefix("[[") {
                let name = h.split("]]").next().unwrap_or("").trim().to_string();
                let n = match counts.iter_mut().find(|(k, _)| *k == name) {
                    Some((_, n)) => {
                        *n += 1;
                        *n
                    }
                    None => {
                        counts.push((name.clone(), 0));
                        0
                    }
                };
                header = Some(format!("{name}[{n}]"));
            } else if let Some(h) = l.strip_prefix('[') {
                header = Some(h.split(']').next().unwrap_or("").trim().to_string());
            }
        }
        match (header, key) {
            (Some(h), Some(k)) => Some(format!("{h}.{k}")),
            (Some(h), None) => Some(h),
            (None, Some(k)) => Some(k),
            (None, None) => None,
        }
    }

    /// Converts a toml (syntax or serde) error into a located [`SpecError`].
    pub(super) fn locate_toml_error(&self, e: &toml::de::Error, syntax: bool) -> SpecError {
        let msg = e.message().trim().to_string();
        let offset = e.span().map_or(0, |s| s.start);
        let mut path = if syntax {
            self.textual_path(offset)
        } else {
            None
        }
        .or_else(|| {
            e.span()
                .and_then(|s| self.path_at(s.start))
                .map(str::to_string)
        })
        .unwrap_or_default();
        let kind = if syntax {
            SpecErrorKind::Syntax
        } else if msg.starts_with("unknown field") {
            SpecErrorKind::UnknownField
        } else if msg.starts_with("missing field") {
            // The span is exactly the enclosing table's (its header or inline braces; the whole
            // document for the root table); name the missing key in the path.
            path = e
                .span()
                .and_then(|s| self.entries.iter().find(|(_, _, _, v)| *v == s))
                .map_or_else(String::new, |(p, _, _, _)| p.clone());
            if let Some(field) = msg.split('`').nth(1) {
                path = if path.is_empty() {
                    field.to_string()
                } else {
                    format!("{path}.{field}")
                };
            }
            SpecErrorKind::MissingField
        } else if msg.starts_with("invalid type")
            || msg.starts_with("invalid length")
            || msg.starts_with("invalid value")
            || msg.starts_with("unknown variant")
            || msg.starts_with("inertia must be")
        {
            SpecErrorKind::WrongType
        } else {
            SpecErrorKind::Invalid
        };
        let msg = if syntax {
            format!("TOML syntax error: {msg}")
        } else {
            msg
        };
        self.error(kind, offset, &path, msg)
    }
}
