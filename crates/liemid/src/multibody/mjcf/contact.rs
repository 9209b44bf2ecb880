//! MJCF `<contact>`: `<exclude body1 body2>` (the pair never touches); `<pair>` is noted as
//! not read (the geoms' own masks decide), and refused when it names a geom the model lacks.
//!
//! Reference: MuJoCo documentation, XML reference, "contact".

use roxmltree::Node;

use super::State;
use crate::error::Result;
use crate::multibody::xml::Built;

impl<'a, 'i> State<'a, 'i> {
    /// The excluded body pairs of the `<contact>` sections, by index into the built bodies
    /// (a merged body stands for the body it was merged into; the world is `None`).
    pub(super) fn read_excludes(
        &mut self,
        sections: &[Node<'a, 'i>],
        built: &Built,
    ) -> Result<Vec<(Option<usize>, Option<usize>)>> {
        let cx = self.cx;
        let mut out = Vec::new();
        for section in sections {
            for node in section.children().filter(Node::is_element) {
                match node.tag_name().name() {
                    "exclude" => {
                        let body = |attr: &str| -> Result<Option<usize>> {
                            let Some(name) = node.attribute(attr) else {
                                return Err(cx.err(node, format!("<exclude> needs {attr}")));
                            };
                            let name = built
                                .merged
                                .iter()
                                .find(|(m, _)| m == name)
                                .map_or(name, |(_, into)| into.as_str());
                            if name == "world" {
                                return Ok(None);
                            }
                            match built.bodies.iter().position(|b| b.name == name) {
                                Some(i) => Ok(Some(i)),
                                None => Err(cx.err(node, format!("{attr}=\"{name}\": no body of that name"))),
                            }
                        };
                        out.push((body("body1")?, body("body2")?));
                    }
                    "pair" => {
                        // Not simulated, but a pair naming a geom the model lacks is an error,
                        // as in MuJoCo.
                        for attr in ["geom1", "geom2"] {
                            let Some(name) = node.attribute(attr) else {
                                return Err(cx.err(node, format!("<pair> needs {attr}")));
                            };
                            let known = node
                                .document()
                                .descendants()
                                .any(|g| g.has_tag_name("geom") && g.attribute("name") == Some(name));
                            if !known {
                                return Err(cx.err(node, format!("{attr}=\"{name}\": no geom of that name")));
                            }
                        }
                        self.ignored
                            .note("contact pair (not read: the geoms' contype and conaffinity decide)");
                    }
                    other => self.ignored.note(&format!("contact {other}")),
                }
            }
        }
        Ok(out)
    }
}
