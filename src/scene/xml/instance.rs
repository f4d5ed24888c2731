//! Mitsuba 3's `shapegroup` and `instance` shapes: a group's shapes are stored once
//! (`SceneDesc::groups`), each instance places them by its `to_world`
//! (`SceneDesc::instances`; see [`crate::scene::instance`] for how they are traced).
//!
//! Mitsuba's rules (`src/render/shapegroup.cpp`, `src/shapes/instance.cpp`): a group holds
//! shapes only, none of them a shape group or an instance and none with an emitter; an
//! instance refers to exactly one shape group; materials stay those of the group's shapes.

use super::{Builder, Elem, Props, Result};
use crate::scene::desc::{GroupDesc, InstanceDesc};
use glam::{Affine3A, Vec4};

impl<'a> Builder<'a> {
    /// `<shape type="shapegroup">` or `<shape type="instance">` (None for other shapes).
    pub(super) fn instancing(
        &mut self,
        e: &'a Elem,
        p: &Props<'a>,
        kind: &str,
    ) -> Option<Result<()>> {
        match kind {
            "shapegroup" => Some(self.shapegroup(e, p).map(|_| ())),
            "instance" => Some(self.instance(e, p)),
            _ => None,
        }
    }

    /// The group of `e`, built the first time it is met (declared, or referred to by an
    /// instance before its declaration).
    fn shapegroup(&mut self, e: &'a Elem, p: &Props<'a>) -> Result<u32> {
        if let Some(&g) = self.groups.get(&(e as *const Elem)) {
            return Ok(g);
        }
        let mut shapes = Vec::new();
        for &obj in &p.objects {
            if obj.tag != "shape" {
                return Err(self.doc.err(
                    obj,
                    format!(
                        "<{}> cannot be nested in a shape group (only shapes)",
                        obj.tag
                    ),
                ));
            }
            match obj.attr("type") {
                Some("shapegroup") => {
                    return Err(self.doc.err(obj, "nested shape groups are not permitted"))
                }
                Some("instance") => {
                    return Err(self.doc.err(
                        obj,
                        "nested instancing is not permitted (an instance in a shape group)",
                    ))
                }
                _ => {}
            }
            self.shape(obj)?;
            let s = self.desc.shapes.pop().expect("shape() adds one shape");
            if s.emission.is_some() {
                return Err(self.doc.err(
                    obj,
                    "instancing of emitters is not supported (a shape in a shape group has an \
                     area emitter)",
                ));
            }
            shapes.push(s);
        }
        p.finish()?;
        let g = self.desc.groups.len() as u32;
        self.desc.groups.push(GroupDesc {
            name: e.attr("id").unwrap_or("(unnamed)").to_string(),
            shapes,
        });
        self.groups.insert(e as *const Elem, g);
        Ok(g)
    }

    fn instance(&mut self, e: &'a Elem, p: &Props<'a>) -> Result<()> {
        let to_world = p.transform("to_world")?;
        let at = p.elem("to_world").unwrap_or(e);
        let mut group = None;
        for &obj in &p.objects {
            // A referred object is reported at its <ref>, an inline one where it stands.
            let place = e
                .children
                .iter()
                .find(|c| {
                    c.tag == "ref" && c.attr("id").is_some() && c.attr("id") == obj.attr("id")
                })
                .unwrap_or(obj);
            if obj.tag != "shape" || obj.attr("type") != Some("shapegroup") {
                return Err(self.doc.err(
                    place,
                    format!(
                        "only a shape group can be specified in an instance, found <{} type=\"{}\">",
                        obj.tag,
                        obj.attr("type").unwrap_or("?")
                    ),
                ));
            }
            if group.is_some() {
                return Err(self.doc.err(
                    place,
                    "only a single shape group can be specified per instance",
                ));
            }
            let gp = self.props(obj)?;
            group = Some(self.shapegroup(obj, &gp)?);
        }
        let Some(group) = group else {
            return Err(self.doc.err(
                e,
                "an instance needs a reference to a shape group (<ref id=\"...\"/>)",
            ));
        };
        if to_world.row(3) != Vec4::W {
            return Err(self.doc.err(
                at,
                "an instance's to_world must be affine (its last row 0 0 0 1)",
            ));
        }
        let to_world = Affine3A::from_mat4(to_world);
        if let Some(why) = crate::scene::instance::singular(&to_world) {
            return Err(self.doc.err(at, format!("an instance's to_world {why}")));
        }
        p.finish()?;
        crate::scene::instance::check_count(self.desc.instances.len() + 1)
            .map_err(|why| self.doc.err(e, why))?;
        self.desc.instances.push(InstanceDesc { group, to_world });
        Ok(())
    }
}
