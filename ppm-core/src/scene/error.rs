//! Errors from reading and checking a scene: each names the file, the field and the value.

use thiserror::Error;

/// Why a scene could not be loaded.
#[derive(Debug, Error)]
pub enum SceneError {
    /// The file could not be read.
    #[error("{file}: cannot read: {reason}")]
    Read {
        /// Scene file.
        file: String,
        /// What the operating system said.
        reason: String,
    },
    /// The file is not valid TOML, or has a field of the wrong type or an unknown field.
    #[error("{file}: {reason}")]
    Syntax {
        /// Scene file.
        file: String,
        /// The parser's message, with line and column.
        reason: String,
    },
    /// A field holds a value the renderer cannot use.
    #[error("{file}: {field} = {value}: {problem}")]
    Invalid {
        /// Scene file (or the source of the values, such as `command line`).
        file: String,
        /// Dotted path of the field, e.g. `materials.red.albedo[1]`.
        field: String,
        /// The offending value as written.
        value: String,
        /// What is wrong with it.
        problem: String,
    },
    /// An element of a Mitsuba or pbrt scene file that we cannot read or render.
    #[error("{file}:{line}: {element}: {problem}")]
    At {
        /// Scene file.
        file: String,
        /// Line of the element (1-based).
        line: u32,
        /// The element or directive as written, e.g. `<bsdf type="plastic">` or `Shape "sphere"`.
        element: String,
        /// What is wrong, or what lies outside the subset we render.
        problem: String,
    },
}

impl SceneError {
    /// Shorthand for [`SceneError::Invalid`].
    pub fn invalid(
        file: &str,
        field: impl Into<String>,
        value: impl std::fmt::Display,
        problem: impl Into<String>,
    ) -> Self {
        Self::Invalid {
            file: file.to_owned(),
            field: field.into(),
            value: value.to_string(),
            problem: problem.into(),
        }
    }
}
