//! Scene-file errors: parse text as `scenes/bad.toml`, and expect an error that names the
//! file, the field and the line.

use dormant::scene::file::{SceneError, SceneFile};

/// `text` parsed as the scene file `scenes/bad.toml`.
pub fn parse(text: &str) -> Result<SceneFile, SceneError> {
    SceneFile::parse("scenes/bad.toml", text)
}

/// `text` is rejected with an error naming the file, `field` and (when given) `line`.
pub fn expect_error(text: &str, field: &str, line: Option<usize>) -> SceneError {
    let err = parse(text).expect_err("scene must be rejected");
    let message = err.to_string();
    assert!(message.contains("scenes/bad.toml"), "{message}");
    assert!(message.contains(field), "expected field {field:?} in {message}");
    assert_eq!(err.field().map(|f| f.contains(field)), Some(true), "{err:?}");
    if let Some(line) = line {
        assert_eq!(err.line(), Some(line), "{message}");
        assert!(message.contains(&format!("bad.toml:{line}")), "{message}");
    }
    err
}
