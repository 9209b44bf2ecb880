//! The refusal check of the model-file tests (MJCF, URDF): included by `#[path]`.

use liemid::error::Error;
use liemid::multibody::Loaded;

/// `r` is a model-file error at `line`, on an element whose text contains `element`, and
/// its message contains every one of `words`.
#[track_caller]
pub fn refused(r: liemid::Result<Loaded>, line: u32, element: &str, words: &[&str]) {
    match r {
        Err(Error::ModelFile {
            line: l,
            element: e,
            message,
            ..
        }) => {
            let shown = format!("{l} <{e}> {message}");
            assert_eq!(l, line, "{shown}");
            assert!(e.contains(element), "{shown}");
            for w in words {
                assert!(message.contains(w), "missing `{w}`: {shown}");
            }
        }
        other => panic!("expected a ModelFile error, got {other:?}"),
    }
}
