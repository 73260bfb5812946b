//! `<shape type="shapegroup">` and `<shape type="instance">`, flattened at load: a group's shapes are
//! read once into object space (materials shared), and each instance copies them into the scene through
//! its `to_world`. What Mitsuba 3.9 refuses in a group (src/render/shapegroup.cpp: another group, an
//! instance, an emitter) is refused here too; an instance holds one group (src/shapes/instance.cpp).

use anyhow::Result;
use glam::{DAffine3, DMat3, DVec3};

use super::elem::Elem;
use super::properties::Props;
use super::{Builder, Group};
use crate::{Mesh, Quad, Sphere, MAX_SHAPES, MAX_TRIANGLES};

impl Group {
    fn triangles(&self) -> usize {
        self.meshes.iter().map(|m| m.indices.len()).sum()
    }
}

impl Builder {
    /// A top-level `<shape type="shapegroup" id="..">`: read, kept by id, not rendered by itself.
    pub(super) fn shapegroup(&mut self, e: &Elem) -> Result<()> {
        let id = e
            .attr("id")
            .ok_or_else(|| e.err("a shapegroup needs an id (instances refer to it by <ref id=\"..\"/>)"))?;
        if self.bsdfs.contains_key(id) || self.textures.contains_key(id) || self.groups.contains_key(id) {
            return Err(e.err(format!(
                "the id \"{id}\" is already taken (ids are unique, as in Mitsuba)"
            )));
        }
        let group = self.group(e)?;
        self.groups.insert(id.to_string(), group);
        Ok(())
    }

    /// The shapes of a shapegroup element, read into the scene and taken out of it again.
    fn group(&mut self, e: &Elem) -> Result<Group> {
        let (props, objects) = Props::of(e);
        props.finish()?;
        let (quads, spheres, meshes) = (
            self.scene.quads.len(),
            self.scene.spheres.len(),
            self.scene.meshes.len(),
        );
        for o in objects {
            if o.tag != "shape" {
                return Err(o.err("a shapegroup holds shapes only (as in Mitsuba)"));
            }
            match o.kind() {
                "shapegroup" => {
                    return Err(o.err("a shapegroup inside a shapegroup: Mitsuba does not permit nesting them"))
                }
                "instance" => {
                    return Err(o.err("an instance inside a shapegroup: Mitsuba does not permit nested instancing"))
                }
                _ => {}
            }
            if let Some(em) = o.children.iter().find(|c| c.tag == "emitter") {
                return Err(em.err("an emitter inside a shapegroup: Mitsuba does not instance emitters"));
            }
            self.shape(o)?;
        }
        // The group's shapes are not the scene's: out they go, with the origins of their indices.
        for (kind, from, to) in [
            ("quad", quads, self.scene.quads.len()),
            ("sphere", spheres, self.scene.spheres.len()),
            ("mesh", meshes, self.scene.meshes.len()),
        ] {
            for i in from..to {
                self.origins.remove(&format!("{kind}[{i}]"));
            }
        }
        let group = Group {
            quads: self.scene.quads.split_off(quads),
            spheres: self.scene.spheres.split_off(spheres),
            meshes: self.scene.meshes.split_off(meshes),
        };
        if group.quads.is_empty() && group.spheres.is_empty() && group.meshes.is_empty() {
            self.warn(e, "an empty shapegroup: its instances add nothing");
        }
        Ok(group)
    }

    /// `<shape type="instance">`: one shapegroup (a `<ref id=".."/>` to a top-level one, or one inline)
    /// and `to_world`; its shapes copied into the scene through `to_world`.
    pub(super) fn instance(&mut self, e: &Elem) -> Result<()> {
        let (props, objects) = Props::of(e);
        let m = props.transform("to_world")?;
        props.finish()?;
        let [o] = objects[..] else {
            return Err(e.err(format!(
                "an instance holds exactly one shapegroup (a <ref id=\"..\"/> or a <shape type=\"shapegroup\">), \
                 not {} objects",
                objects.len()
            )));
        };
        let inline;
        let group = match (o.tag.as_str(), o.kind()) {
            ("ref", _) => {
                let id = o.required("id")?;
                self.groups.get(id).ok_or_else(|| {
                    let mut known: Vec<&str> = self.groups.keys().map(String::as_str).collect();
                    known.sort();
                    o.err(format!(
                        "no shapegroup with id \"{id}\" defined before it (known: {})",
                        if known.is_empty() {
                            "none".to_string()
                        } else {
                            known.join(", ")
                        }
                    ))
                })?
            }
            ("shape", "shapegroup") => {
                inline = self.group(o)?;
                &inline
            }
            _ => return Err(o.err("an instance holds a shapegroup only (as in Mitsuba)")),
        };
        let det = m.matrix3.determinant();
        if !det.is_finite() || det == 0.0 {
            return Err(e.err("to_world is singular: it flattens the instance"));
        }
        // The bounds, before anything is copied.
        let shapes = self.scene.quads.len() + self.scene.spheres.len() + group.quads.len() + group.spheres.len();
        if shapes > MAX_SHAPES {
            return Err(e.err(format!(
                "instancing brings the scene to {shapes} spheres and quads, more than MAX_SHAPES = {MAX_SHAPES}"
            )));
        }
        let triangles = self.scene.meshes.iter().map(|m| m.indices.len()).sum::<usize>() + group.triangles();
        if triangles > MAX_TRIANGLES {
            return Err(e.err(format!(
                "instancing brings the scene to {triangles} triangles, more than MAX_TRIANGLES = {MAX_TRIANGLES}"
            )));
        }
        let placed = place(e, group, &m, &self.scene.materials)?;
        for (kind, from, n) in [
            ("quad", self.scene.quads.len(), placed.quads.len()),
            ("sphere", self.scene.spheres.len(), placed.spheres.len()),
            ("mesh", self.scene.meshes.len(), placed.meshes.len()),
        ] {
            for i in from..from + n {
                self.origins.insert(format!("{kind}[{i}]"), e.clone());
            }
        }
        self.scene.quads.extend(placed.quads);
        self.scene.spheres.extend(placed.spheres);
        self.scene.meshes.extend(placed.meshes);
        Ok(())
    }
}

/// `group`'s shapes through `m` (non-singular): positions by `m`, normals by its inverse transpose (as
/// Mitsuba's instance turns them), a mirroring `m` reversing the winding so that the front side stays the
/// one the normal gives (as for a mirrored mesh).
fn place(e: &Elem, group: &Group, m: &DAffine3, materials: &[crate::Material]) -> Result<Group> {
    let mirrors = m.matrix3.determinant() < 0.0;
    let finite = |v: glam::Vec3, what: &str| {
        if v.is_finite() {
            Ok(v)
        } else {
            Err(e.err(format!("to_world takes {what} beyond f32 (it is {v})")))
        }
    };
    let at = |p: glam::Vec3| m.transform_point3(p.as_dvec3()).as_vec3();
    let along = |v: glam::Vec3| m.transform_vector3(v.as_dvec3()).as_vec3();
    let mut quads = Vec::with_capacity(group.quads.len());
    for q in &group.quads {
        let material = &materials[q.material as usize];
        let oriented = material.texture.is_some() || material.surface.rough().is_some_and(|r| r.is_anisotropic());
        if mirrors && oriented {
            return Err(e.err(
                "a mirroring to_world on an instance of a textured or anisotropic rectangle or cube is not \
                 supported (its texture coordinates or tangents would turn)",
            ));
        }
        let (mut u, mut v) = (along(q.edge_u), along(q.edge_v));
        if mirrors {
            std::mem::swap(&mut u, &mut v);
        }
        quads.push(Quad {
            origin: finite(at(q.origin), "a quad's corner")?,
            edge_u: finite(u, "a quad's edge")?,
            edge_v: finite(v, "a quad's edge")?,
            material: q.material,
            disk: q.disk,
        });
    }
    // A sphere stays one under a similarity only: m^T m = s^2 I.
    let gram = m.matrix3.transpose() * m.matrix3;
    let s2 = gram.x_axis.x;
    let similar = (gram - DMat3::from_diagonal(DVec3::splat(s2)))
        .to_cols_array()
        .iter()
        .all(|x| x.abs() <= 1e-6 * s2);
    let turns = (m.matrix3 * (1.0 / s2.sqrt()) - DMat3::IDENTITY)
        .to_cols_array()
        .iter()
        .any(|x| x.abs() > 1e-6);
    let mut spheres = Vec::with_capacity(group.spheres.len());
    for s in &group.spheres {
        if !similar {
            return Err(e.err("to_world scales the instance's sphere non-uniformly (an ellipsoid): not supported"));
        }
        let material = &materials[s.material as usize];
        if turns && (material.texture.is_some() || material.surface.rough().is_some_and(|r| r.is_anisotropic())) {
            return Err(e.err(
                "a to_world that rotates or mirrors an instance of a textured or anisotropic sphere is not \
                 supported (its texture coordinates and tangents are taken along the world's axes)",
            ));
        }
        spheres.push(Sphere {
            center: finite(at(s.center), "a sphere's centre")?,
            radius: (f64::from(s.radius) * s2.sqrt()) as f32,
            material: s.material,
        });
    }
    let normal_matrix = m.matrix3.inverse().transpose();
    let mut meshes = Vec::with_capacity(group.meshes.len());
    for mesh in &group.meshes {
        let positions = mesh
            .positions
            .iter()
            .map(|&p| finite(at(p), "a vertex"))
            .collect::<Result<Vec<_>>>()?;
        let normals = mesh.normals.as_ref().map(|n| {
            n.iter()
                .map(|&n| (normal_matrix * n.as_dvec3()).normalize().as_vec3())
                .collect()
        });
        let mut indices = mesh.indices.clone();
        if mirrors {
            indices.iter_mut().for_each(|t| t.swap(1, 2));
        }
        meshes.push(Mesh {
            name: mesh.name.clone(),
            positions,
            normals,
            uvs: mesh.uvs.clone(),
            indices,
            materials: mesh.materials.clone(),
        });
    }
    Ok(Group { quads, spheres, meshes })
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::super::tests::{error, load_body};
    use crate::Scene;

    /// A group of a rectangle, a sphere and a disk (a mesh), each with its own `to_world`.
    const GROUP: &str = r#"<shape type="shapegroup" id="g">
        <shape type="rectangle"><transform name="to_world"><scale value="1.2"/><rotate y="1" angle="-80"/></transform>
            <bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.9 0.5 0.9"/></bsdf></bsdf></shape>
        <shape type="sphere"><transform name="to_world"><scale value="0.5"/><translate value="-1 0 0"/></transform>
            <bsdf type="diffuse"><rgb name="reflectance" value="0.9 0.5 0.3"/></bsdf></shape>
        <shape type="disk"><transform name="to_world"><rotate x="1" angle="30"/><translate z="0.5"/></transform>
            <bsdf type="twosided"><bsdf type="diffuse"/></bsdf></shape>
    </shape>"#;

    /// The group's shapes written out with `instance` after each one's own transform: what an instance
    /// through `instance` must give.
    fn flattened(instance: &str) -> String {
        format!(
            r#"<shape type="rectangle"><transform name="to_world"><scale value="1.2"/><rotate y="1" angle="-80"/>{instance}</transform>
                <bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.9 0.5 0.9"/></bsdf></bsdf></shape>
            <shape type="sphere"><transform name="to_world"><scale value="0.5"/><translate value="-1 0 0"/>{instance}</transform>
                <bsdf type="diffuse"><rgb name="reflectance" value="0.9 0.5 0.3"/></bsdf></shape>
            <shape type="disk"><transform name="to_world"><rotate x="1" angle="30"/><translate z="0.5"/>{instance}</transform>
                <bsdf type="twosided"><bsdf type="diffuse"/></bsdf></shape>"#
        )
    }

    fn same_scenes(a: &Scene, b: &Scene, what: &str) {
        let close = |x: Vec3, y: Vec3| x.distance(y) <= 1e-5 * x.length().max(1.0);
        assert_eq!(a.quads.len(), b.quads.len(), "{what}");
        for (p, q) in a.quads.iter().zip(&b.quads) {
            assert!(
                close(p.origin, q.origin) && close(p.edge_u, q.edge_u) && close(p.edge_v, q.edge_v),
                "{what}: {p:?} vs {q:?}"
            );
            let (m, n) = (&a.materials[p.material as usize], &b.materials[q.material as usize]);
            assert_eq!((m.surface, m.emission), (n.surface, n.emission), "{what}");
        }
        assert_eq!(a.spheres.len(), b.spheres.len(), "{what}");
        for (p, q) in a.spheres.iter().zip(&b.spheres) {
            assert!(
                close(p.center, q.center) && (p.radius - q.radius).abs() < 1e-6,
                "{what}: {p:?} vs {q:?}"
            );
        }
        assert_eq!(a.meshes.len(), b.meshes.len(), "{what}");
        for (m, n) in a.meshes.iter().zip(&b.meshes) {
            assert_eq!(m.indices.len(), n.indices.len(), "{what}");
            // Corner by corner (the flattened mesh numbers its vertices in another order).
            for (s, t) in m.triangles().zip(n.triangles()) {
                assert!(s.p.iter().zip(t.p).all(|(p, q)| close(*p, q)), "{what}: {s:?} vs {t:?}");
            }
        }
    }

    /// Each instance is its group's shapes placed by the instance's to_world after their own (a
    /// translation, a rotation with a uniform scale, a mirror): the same quads (corners and front side),
    /// spheres and mesh (positions, winding) as the shapes written out with both transforms. The group by
    /// itself adds nothing.
    #[test]
    fn an_instance_is_its_group_placed_by_to_world() {
        let alone = load_body(GROUP).unwrap();
        assert_eq!(
            (alone.quads.len(), alone.spheres.len(), alone.meshes.len()),
            (1, 0, 0),
            "the lamp only"
        );
        for instance in [
            "",
            r#"<translate z="2"/>"#,
            r#"<rotate y="1" angle="45"/><scale value="1.5"/><translate z="2"/>"#,
            r#"<scale x="-1"/><translate x="3"/>"#,
        ] {
            let got = load_body(&format!(
                r#"{GROUP}<shape type="instance"><ref id="g"/><transform name="to_world">{instance}</transform></shape>"#
            ))
            .unwrap_or_else(|e| panic!("{instance}: {e:#}"));
            let want = load_body(&flattened(instance)).unwrap();
            same_scenes(&got, &want, instance);
            got.validate().unwrap();
        }
        // Two instances, and one holding its group inline.
        let two = load_body(&format!(
            r#"{GROUP}<shape type="instance"><ref id="g"/></shape>
               <shape type="instance"><ref id="g"/><transform name="to_world"><translate z="2"/></transform></shape>"#
        ))
        .unwrap();
        let want = load_body(&format!("{}{}", flattened(""), flattened(r#"<translate z="2"/>"#))).unwrap();
        assert_eq!((two.quads.len(), two.spheres.len(), two.meshes.len()), (3, 2, 2));
        same_scenes(&two, &want, "two instances");
        let inline = GROUP.replace(r#" id="g""#, "");
        let one = load_body(&format!(r#"<shape type="instance">{inline}</shape>"#)).unwrap();
        same_scenes(&one, &load_body(&flattened("")).unwrap(), "inline");
    }

    #[test]
    fn what_mitsuba_refuses_in_groups_and_instances_is_refused() {
        let cases: &[(&str, &str, &str)] = &[
            (
                r#"<shape type="shapegroup" id="g"><shape type="cube"><emitter type="area"/></shape></shape>"#,
                r#"<emitter type="area">"#,
                "an emitter inside a shapegroup",
            ),
            (
                r#"<shape type="shapegroup" id="g"><shape type="shapegroup" id="h"/></shape>"#,
                r#"<shape type="shapegroup" id="h">"#,
                "does not permit nesting",
            ),
            (
                r#"<shape type="shapegroup" id="g"/><shape type="shapegroup" id="h"><shape type="instance"><ref id="g"/></shape></shape>"#,
                r#"<shape type="instance">"#,
                "nested instancing",
            ),
            (
                r#"<shape type="instance"><ref id="nowhere"/></shape>"#,
                r#"<ref id="nowhere">"#,
                "no shapegroup with id \"nowhere\" defined before it (known: none)",
            ),
            (
                r#"<shape type="instance"><ref id="g"/></shape><shape type="shapegroup" id="g"/>"#,
                r#"<ref id="g">"#,
                "no shapegroup with id \"g\" defined before it",
            ),
            (
                r#"<shape type="instance"/>"#,
                r#"<shape type="instance">"#,
                "exactly one shapegroup",
            ),
            (
                r#"<shape type="shapegroup"/>"#,
                r#"<shape type="shapegroup">"#,
                "needs an id",
            ),
            (
                r#"<bsdf type="diffuse" id="g"/><shape type="shapegroup" id="g"/>"#,
                r#"<shape type="shapegroup" id="g">"#,
                "already taken",
            ),
            (
                r#"<shape type="shapegroup" id="g"><shape type="sphere"/></shape>
                   <shape type="instance"><ref id="g"/><transform name="to_world"><scale y="2"/></transform></shape>"#,
                r#"<shape type="instance">"#,
                "non-uniformly",
            ),
            (
                r#"<shape type="shapegroup" id="g"><shape type="cube"/></shape>
                   <shape type="instance"><ref id="g"/><transform name="to_world"><scale y="0"/></transform></shape>"#,
                r#"<shape type="instance">"#,
                "singular",
            ),
        ];
        for (body, element, says) in cases {
            let e = error(body);
            assert!(e.contains(element) && e.contains(says), "{body}: {e}");
        }
    }
}
