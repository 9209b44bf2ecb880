//! MJCF `<include file>`: the element is replaced by the children of the included file's
//! `<mujoco>` root, as MuJoCo does, so a scene (`scene.xml` of MuJoCo Menagerie, which
//! includes the robot and adds a floor and lights) loads as it is.
//!
//! Decisions:
//! - A relative `file` is resolved as in MuJoCo: against the directory of the main model
//!   file, else against the directory of the file that includes it.
//! - Includes nest at most [`MAX_INCLUDE_DEPTH`] deep; a file that includes itself,
//!   directly or through others, is refused naming the chain, and so is a file included a
//!   second time anywhere in the model (MuJoCo's "already included": it also bounds the
//!   work); the assembled text is bounded by the 64 MiB of one model file, and every file
//!   is parsed within the same bounds as the main one (size, no DTD, node count, nesting)
//!   before it is spliced.
//! - Errors name the file and line where the element stands, not the assembled text's.
//!
//! Reference: MuJoCo documentation, *XML Reference*, `include`
//! (<https://mujoco.readthedocs.io/en/stable/XMLreference.html#include>).

use std::path::{Path, PathBuf};

use roxmltree::Node;

use super::super::xml::{file_error, line_of, line_starts, parse_document, read_bounded, Ctx, Sources, MAX_FILE_BYTES};
use crate::error::Result;

/// Deepest chain of includes accepted (the main file is depth 0).
pub const MAX_INCLUDE_DEPTH: usize = 16;

/// The text of the model file `path` with every `<include>` replaced by the included
/// file's content, where each piece of it came from, and every file read (the main file
/// first).
pub(super) fn expand(path: &Path) -> Result<(String, Sources, Vec<PathBuf>)> {
    let text = read_bounded(path)?;
    let mut assembler = Assembler {
        base: path.parent().map(Path::to_path_buf).unwrap_or_default(),
        out: String::with_capacity(text.len()),
        sources: Sources::default(),
        chain: vec![canonical(path)],
        seen: vec![canonical(path)],
        main: path.display().to_string(),
    };
    let name = assembler.main.clone();
    let dir = assembler.base.clone();
    assembler.splice(&text, &name, &dir, true)?;
    Ok((assembler.out, assembler.sources, assembler.seen))
}

struct Assembler {
    /// The main file's directory, against which relative includes are resolved.
    base: PathBuf,
    out: String,
    sources: Sources,
    /// The files being included, outermost first (to refuse cycles).
    chain: Vec<PathBuf>,
    /// Every file read so far (to refuse a second inclusion).
    seen: Vec<PathBuf>,
    main: String,
}

/// The file's path with links and `..` resolved where it exists (to compare files).
fn canonical(path: &Path) -> PathBuf {
    path.canonicalize().unwrap_or_else(|_| path.to_path_buf())
}

impl Assembler {
    /// Appends `text` (all of it for the main file, else its root's content) to the output,
    /// with its includes expanded; `dir` is the file's own directory.
    fn splice(&mut self, text: &str, name: &str, dir: &Path, main: bool) -> Result<()> {
        let doc = parse_document(text, name, Sources::NONE)?;
        let lines = line_starts(text);
        let cx = Ctx::new(name, Sources::NONE, &lines);
        let root = doc.root_element();
        let range = if main {
            0..text.len()
        } else {
            if root.tag_name().name() != "mujoco" {
                return Err(cx.err(root, "an included file's root element must be <mujoco>"));
            }
            match (root.first_child(), root.last_child()) {
                (Some(first), Some(last)) => first.range().start..last.range().end,
                _ => 0..0,
            }
        };
        let includes: Vec<Node> = root.descendants().filter(|n| n.has_tag_name("include")).collect();
        let mut at = range.start;
        for include in includes {
            self.push(text, at, include.range().start, name)?;
            let file = include
                .attribute("file")
                .ok_or_else(|| cx.err(include, "<include> needs a `file` attribute"))?;
            if include.children().any(|c| c.is_element()) {
                return Err(cx.err(include, "<include> cannot have child elements"));
            }
            if self.chain.len() > MAX_INCLUDE_DEPTH {
                return Err(cx.err(
                    include,
                    format!("includes nested deeper than {MAX_INCLUDE_DEPTH} files are refused"),
                ));
            }
            let in_main = self.base.join(file);
            let path = if in_main.exists() { in_main } else { dir.join(file) };
            let id = canonical(&path);
            if let Some(k) = self.chain.iter().position(|p| *p == id) {
                let cycle: Vec<String> = self.chain[k..]
                    .iter()
                    .chain(std::iter::once(&id))
                    .map(|p| p.display().to_string())
                    .collect();
                return Err(cx.err(include, format!("the file includes itself: {}", cycle.join(" -> "))));
            }
            if self.seen.contains(&id) {
                return Err(cx.err(
                    include,
                    format!("`{}` is already included in this model", path.display()),
                ));
            }
            let included = read_bounded(&path)
                .map_err(|e| cx.err(include, format!("cannot include `{}`: {e}", path.display())))?;
            self.seen.push(id.clone());
            self.chain.push(id);
            let own_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
            self.splice(&included, &path.display().to_string(), &own_dir, false)?;
            self.chain.pop();
            at = include.range().end;
        }
        self.push(text, at, range.end, name)
    }

    /// Appends `text[from..to]` of file `name`, refusing an assembled text over the bound.
    fn push(&mut self, text: &str, from: usize, to: usize, name: &str) -> Result<()> {
        if from < to {
            self.sources.push(self.out.len(), name, line_of(text, from));
            self.out.push_str(&text[from..to]);
        }
        if self.out.len() as u64 > MAX_FILE_BYTES {
            return Err(file_error(
                &self.main,
                format!(
                    "larger than the {} MiB accepted for a model once its includes are expanded",
                    MAX_FILE_BYTES >> 20
                ),
            ));
        }
        Ok(())
    }
}
