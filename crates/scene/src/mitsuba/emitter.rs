//! The `<emitter>` element: Mitsuba's area emitter inside a shape (its radiance), and the lights with no
//! surface of their own at the top level (point, spot, directional, constant, envmap), read with Mitsuba
//! 3's parameters and defaults into `Scene::emitters`.

use std::rc::Rc;

use anyhow::Result;
use glam::{DAffine3, DMat3, DVec3, Mat3, Vec3};

use super::elem::Elem;
use super::properties::Props;
use super::texture::Tex;
use super::Builder;
use crate::emitter::{Emitter, EnvMap, Environment};
use crate::texture;

impl Builder {
    /// A top-level `<emitter>`: one light of `Scene::emitters` (`emitter[i]` in check messages, located
    /// at this element or at the property a failed check names).
    pub(super) fn emitter(&mut self, e: &Elem) -> Result<()> {
        let (props, objects) = Props::of(e);
        if let Some(o) = objects.first() {
            return Err(o.err(format!("not expected inside {}", e.what())));
        }
        let path = format!("emitter[{}]", self.scene.emitters.len());
        // Check paths (`emitter[i].<field>`) -> the property the field came from.
        let mut fields: Vec<(&str, &Elem)> = Vec::new();
        let mut field = |name: &'static str, property: &str| {
            if let Some(p) = props.get(property) {
                fields.push((name, p));
            }
        };
        // Every Mitsuba 3 emitter's relative chance of being chosen for a shadow ray: its noise only.
        props.ignore(&["sampling_weight"]);
        let light = match e.kind() {
            "point" => {
                field("intensity", "intensity");
                field("position", "position");
                field("position", "to_world");
                let intensity = props.color("intensity")?.unwrap_or(Vec3::ONE);
                let position = match (props.point("position")?, props.get("to_world")) {
                    (Some(_), Some(t)) => return Err(exclusive(e, t, "position")),
                    (Some(p), None) => p,
                    (None, _) => props.transform("to_world")?.translation,
                };
                Emitter::Point {
                    position: position.as_vec3(),
                    intensity,
                }
            }
            "spot" => {
                field("intensity", "intensity");
                field("cutoff_angle", "cutoff_angle");
                field("beam_width", "beam_width");
                field("position", "to_world");
                field("direction", "to_world");
                if let Some(t) = props.get("texture") {
                    return Err(t.err("a spot's projected texture is not supported"));
                }
                let intensity = props.color("intensity")?.unwrap_or(Vec3::ONE);
                let cutoff = props.float("cutoff_angle")?.unwrap_or(20.0);
                let beam = props.float("beam_width")?.unwrap_or(cutoff * 0.75);
                let to_world = props.transform("to_world")?;
                // Mitsuba measures the cone's angles in local space: a transform that does not keep angles
                // would make it elliptical.
                if !conformal(&to_world.matrix3) {
                    let t = props.get("to_world").unwrap_or(e);
                    return Err(t.err(format!(
                        "the to_world of {} scales non-uniformly or shears: a spot's cone must stay round \
                         (give a rotation and translation, e.g. a lookat)",
                        e.what()
                    )));
                }
                Emitter::Spot {
                    position: to_world.translation.as_vec3(),
                    direction: to_world.matrix3.z_axis.normalize().as_vec3(),
                    intensity,
                    cutoff: cutoff.to_radians() as f32,
                    beam: beam.to_radians() as f32,
                }
            }
            "directional" => {
                field("irradiance", "irradiance");
                field("direction", "direction");
                field("direction", "to_world");
                let irradiance = props.color("irradiance")?.unwrap_or(Vec3::ONE);
                let (direction, at) = match (props.point("direction")?, props.get("to_world")) {
                    (Some(_), Some(t)) => return Err(exclusive(e, t, "direction")),
                    (Some(d), None) => (d, props.get("direction").unwrap_or(e)),
                    // Local +z is the way the light travels.
                    (None, t) => (props.transform("to_world")?.matrix3.z_axis, t.unwrap_or(e)),
                };
                if direction.length() == 0.0 {
                    return Err(at.err(format!("the direction of {} is zero", e.what())));
                }
                Emitter::Directional {
                    direction: direction.normalize().as_vec3(),
                    irradiance,
                }
            }
            "constant" => {
                field("radiance", "radiance");
                field("to_world", "to_world");
                let scale = props.color("radiance")?.unwrap_or(Vec3::ONE);
                let to_world = environment_to_world(e, &props)?;
                Emitter::Environment(Environment {
                    scale,
                    map: None,
                    to_world,
                })
            }
            "envmap" => {
                field("scale", "scale");
                field("filename", "filename");
                field("to_world", "to_world");
                let file = self.file(e, &props)?;
                let scale = props.float("scale")?.unwrap_or(1.0) as f32;
                // Mitsuba's hint for its sampling when combined by MIS: the image is the same.
                props.boolean("mis_compensation")?;
                let to_world = environment_to_world(e, &props)?;
                props.finish()?;
                let shown = file.display().to_string();
                // As Mitsuba: 8- and 16-bit images are sRGB-encoded, EXR and HDR (RGBE) linear.
                let (width, height, pixels) =
                    texture::read_image(&file, false).map_err(|m| e.err(format!("{shown}: {m}")))?;
                Emitter::Environment(Environment {
                    scale: Vec3::splat(scale),
                    map: Some(EnvMap {
                        name: shown,
                        width,
                        height,
                        pixels,
                    }),
                    to_world,
                })
            }
            "area" => return Err(e.err("an area emitter belongs inside a shape (it is that shape's light)")),
            _ => {
                return Err(e.err(
                    "unsupported emitter (read: point, spot, directional, constant, envmap; and area inside \
                     a shape)",
                ))
            }
        };
        props.finish()?;
        self.origins.insert(path.clone(), e.clone());
        for (name, p) in fields {
            self.origins.insert(format!("{path}.{name}"), p.clone());
        }
        self.scene.emitters.push(light);
        Ok(())
    }
}

/// `position` (or `direction`) and `to_world` both given: Mitsuba refuses that too.
fn exclusive(e: &Elem, to_world: &Elem, other: &str) -> anyhow::Error {
    to_world.err(format!(
        "{} has both {other} and to_world: give one (as Mitsuba requires)",
        e.what()
    ))
}

/// Whether `m` keeps angles: orthogonal columns of one length (a rotation, perhaps mirrored, times a
/// uniform scale).
fn conformal(m: &DMat3) -> bool {
    let gram = m.transpose() * *m;
    let s2 = gram.x_axis.x;
    s2 > 0.0
        && (gram - DMat3::from_diagonal(DVec3::splat(s2)))
            .to_cols_array()
            .iter()
            .all(|x| x.abs() <= 1e-6 * s2)
}

/// An environment's `to_world`: its rotation (a translation does not move what is infinitely far). A scale
/// or shear is refused here, naming the emitter: Mitsuba would distort the map's directions.
fn environment_to_world(e: &Elem, props: &Props) -> Result<Mat3> {
    let m: DAffine3 = props.transform("to_world")?;
    let gram = m.matrix3.transpose() * m.matrix3;
    if (gram - DMat3::IDENTITY).to_cols_array().iter().any(|x| x.abs() > 1e-3) {
        let t = props.get("to_world").unwrap_or(e);
        return Err(t.err(format!(
            "the to_world of {} scales or shears: an environment's to_world must be a rotation",
            e.what()
        )));
    }
    Ok(m.matrix3.as_mat3())
}

impl Builder {
    /// The radiance of an `<emitter>` inside a shape (Mitsuba's default 1): a colour, or a texture (nested,
    /// or a `ref` to a top-level one), as Mitsuba 3's src/emitters/area.cpp reads it: Le at each point from
    /// the shape's uv. A texture's values are radiances: unbounded (finite and at least 0: the scene's check).
    pub(super) fn area(&self, o: &Elem) -> Result<(Vec3, Option<Rc<Tex>>)> {
        if o.kind() != "area" {
            return Err(o.err(format!(
                "a {} emitter inside a shape: only area emitters belong on shapes (put the others at the top level)",
                o.kind()
            )));
        }
        let (ep, rest) = Props::of(o);
        if let Some(r) = rest.first() {
            return Err(r.err(format!("not expected inside {}", o.what())));
        }
        let texture = match ep.get("radiance") {
            Some(p) if p.tag == "texture" => Some(Rc::new(self.texture(p)?)),
            Some(p) if p.tag == "ref" => {
                let id = p.required("id")?;
                Some(
                    self.textures
                        .get(id)
                        .cloned()
                        .ok_or_else(|| p.err(format!("no texture with id \"{id}\" defined before it")))?,
                )
            }
            _ => None,
        };
        let radiance = match &texture {
            Some(_) => Vec3::ZERO, // set by the caller from the texture (Material::emission)
            None => ep.color("radiance")?.unwrap_or(Vec3::ONE),
        };
        ep.ignore(&["sampling_weight"]); // Mitsuba's chance of choosing it for a shadow ray: noise only
        ep.finish()?;
        Ok((radiance, texture))
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{error, load_body, load_in};
    use super::*;
    use crate::TempDir;

    /// The one light of `body` (after the test head's emitting rectangle).
    fn light(body: &str) -> Emitter {
        let s = load_body(body).unwrap_or_else(|e| panic!("{e:#}"));
        assert_eq!(s.emitters.len(), 1, "{body}");
        s.emitters[0].clone()
    }

    fn close(a: Vec3, b: Vec3) -> bool {
        a.distance(b) < 1e-5
    }

    #[test]
    fn each_light_with_mitsubas_defaults() {
        assert_eq!(
            light(r#"<emitter type="point"/>"#),
            Emitter::Point {
                position: Vec3::ZERO,
                intensity: Vec3::ONE
            }
        );
        // Cutoff 20 degrees, beam 3/4 of it; the axis local +z.
        assert_eq!(
            light(r#"<emitter type="spot"/>"#),
            Emitter::Spot {
                position: Vec3::ZERO,
                direction: Vec3::Z,
                intensity: Vec3::ONE,
                cutoff: 20f32.to_radians(),
                beam: 15f32.to_radians(),
            }
        );
        // A given cutoff sets the default beam.
        let Emitter::Spot { cutoff, beam, .. } =
            light(r#"<emitter type="spot"><float name="cutoff_angle" value="40"/></emitter>"#)
        else {
            panic!("a spot")
        };
        assert!((cutoff - 40f32.to_radians()).abs() < 1e-6 && (beam - 30f32.to_radians()).abs() < 1e-6);
        assert_eq!(
            light(r#"<emitter type="directional"/>"#),
            Emitter::Directional {
                direction: Vec3::Z,
                irradiance: Vec3::ONE
            }
        );
        assert_eq!(
            light(r#"<emitter type="constant"/>"#),
            Emitter::Environment(Environment {
                scale: Vec3::ONE,
                map: None,
                to_world: Mat3::IDENTITY
            })
        );
    }

    #[test]
    fn each_light_with_every_parameter() {
        assert_eq!(
            light(
                r#"<emitter type="point"><point name="position" x="1" y="2" z="3"/><rgb name="intensity" value="1, 2, 3"/></emitter>"#
            ),
            Emitter::Point {
                position: Vec3::new(1.0, 2.0, 3.0),
                intensity: Vec3::new(1.0, 2.0, 3.0)
            }
        );
        // to_world's translation is the position; a light's spectrum of one value is, as in Mitsuba 3's RGB
        // variants, that value times xyz_to_srgb(1, 1, 1) (a flat spectrum is not D65's white), not grey: Mitsuba
        // 3 gives (6.023969650268555, 4.741455078125, 4.544580459594727) (scenes/references/spectra.json).
        assert_eq!(
            light(
                r#"<emitter type="point"><transform name="to_world"><rotate y="1" angle="30"/><translate x="-1" z="2"/></transform>
                   <spectrum name="intensity" value="5"/></emitter>"#
            ),
            Emitter::Point {
                position: Vec3::new(-1.0, 0.0, 2.0),
                intensity: Vec3::new(6.023_969_7, 4.741_455, 4.544_580_5)
            }
        );
        // Mitsuba's lookat: origin the position, +z towards the target.
        let Emitter::Spot {
            position,
            direction,
            intensity,
            cutoff,
            beam,
        } = light(
            r#"<emitter type="spot"><rgb name="intensity" value="10, 20, 30"/><float name="cutoff_angle" value="30"/>
               <float name="beam_width" value="10"/>
               <transform name="to_world"><lookat origin="1, 4, 1" target="1, 0, 1" up="0, 0, 1"/></transform></emitter>"#,
        )
        else {
            panic!("a spot")
        };
        assert!(close(position, Vec3::new(1.0, 4.0, 1.0)), "{position}");
        assert!(close(direction, Vec3::NEG_Y), "{direction}");
        assert_eq!(intensity, Vec3::new(10.0, 20.0, 30.0));
        assert!((cutoff - 30f32.to_radians()).abs() < 1e-6 && (beam - 10f32.to_radians()).abs() < 1e-6);
        // A uniform scale keeps the cone round: allowed, the axis still unit.
        let Emitter::Spot { direction, .. } = light(
            r#"<emitter type="spot"><transform name="to_world"><scale value="2"/><rotate x="1" angle="90"/></transform></emitter>"#,
        ) else {
            panic!("a spot")
        };
        assert!(close(direction, Vec3::NEG_Y), "{direction}");
        // The direction light travels, normalised; or to_world's +z.
        assert_eq!(
            light(
                r#"<emitter type="directional"><vector name="direction" x="0" y="-2" z="0"/><float name="irradiance" value="3"/></emitter>"#
            ),
            Emitter::Directional {
                direction: Vec3::NEG_Y,
                irradiance: Vec3::splat(3.0)
            }
        );
        let Emitter::Directional { direction, .. } = light(
            r#"<emitter type="directional"><transform name="to_world"><lookat origin="0, 0, 0" target="1, -1, 0" up="0, 1, 0"/></transform></emitter>"#,
        ) else {
            panic!("a directional")
        };
        assert!(close(direction, Vec3::new(1.0, -1.0, 0.0).normalize()), "{direction}");
        let Emitter::Environment(env) = light(
            r#"<emitter type="constant"><rgb name="radiance" value="0.5, 1, 2"/>
               <transform name="to_world"><rotate y="1" angle="90"/></transform></emitter>"#,
        ) else {
            panic!("an environment")
        };
        assert_eq!((env.scale, env.map), (Vec3::new(0.5, 1.0, 2.0), None));
        assert!(close(env.to_world * Vec3::Z, Vec3::X), "{}", env.to_world);
    }

    /// Writes `name` in `dir`: a 4 x 2 float image whose pixel (x, y) is `value(x, y)`, saved in the format
    /// its extension names.
    fn write_float_image(dir: &TempDir, name: &str, value: impl Fn(u32, u32) -> [f32; 3]) {
        let img = image::Rgb32FImage::from_fn(4, 2, |x, y| image::Rgb(value(x, y)));
        img.save(dir.0.join(name)).expect("writing a test image");
    }

    fn envmap(dir: &TempDir, extra: &str) -> Result<Environment> {
        let s = load_in(
            dir,
            &format!(r#"<emitter type="envmap"><string name="filename" value="maps/sky.{extra}</emitter>"#),
            &[],
        )?;
        match &s.emitters[..] {
            [Emitter::Environment(env)] => Ok(env.clone()),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn envmaps_read_back_from_exr_hdr_and_png() {
        let dir = TempDir::new("mitsuba-envmap");
        std::fs::create_dir_all(dir.0.join("maps")).unwrap();
        // Powers of two within a factor 256 of each pixel's largest: exact in RGBE too.
        let value = |x: u32, y: u32| [(1 << x) as f32, 0.5 * (y + 1) as f32, 0.25];
        write_float_image(&dir, "maps/sky.exr", value);
        write_float_image(&dir, "maps/sky.hdr", value);
        for ext in ["exr", "hdr"] {
            let env = envmap(&dir, &format!("{ext}\"/>")).unwrap_or_else(|e| panic!("{ext}: {e:#}"));
            let map = env.map.expect("a map");
            assert_eq!((map.width, map.height), (4, 2), "{ext}");
            assert!(map.name.ends_with(&format!("maps/sky.{ext}")), "{}", map.name);
            for (k, p) in map.pixels.iter().enumerate() {
                let want = Vec3::from_array(value(k as u32 % 4, k as u32 / 4));
                assert!(
                    close(*p, want),
                    "{ext}: pixel {k} is {p}, want {want} (linear, top row first)"
                );
            }
            assert_eq!((env.scale, env.to_world), (Vec3::ONE, Mat3::IDENTITY));
        }
        // PNG: sRGB-encoded, decoded to linear.
        let rgb: Vec<u8> = (0..8).flat_map(|k| [255, 128, (k * 30) as u8]).collect();
        texture::write_png(&dir.0.join("maps/sky.png"), 4, 2, &rgb);
        let env = envmap(
            &dir,
            r#"png"/><float name="scale" value="2.5"/><boolean name="mis_compensation" value="true"/><float name="sampling_weight" value="0.5"/>
               <transform name="to_world"><rotate x="1" angle="-90"/><translate y="7"/></transform>"#,
        )
        .unwrap_or_else(|e| panic!("{e:#}"));
        let map = env.map.expect("a map");
        for (k, p) in map.pixels.iter().enumerate() {
            let want = Vec3::new(
                1.0,
                texture::srgb_to_linear(128.0 / 255.0),
                texture::srgb_to_linear((k * 30) as f32 / 255.0),
            );
            assert!(close(*p, want), "pixel {k} is {p}, want {want}");
        }
        assert_eq!(env.scale, Vec3::splat(2.5));
        // The rotation only (the translation does not move what is infinitely far): local +y is world -z.
        assert!(close(env.to_world * Vec3::Y, Vec3::NEG_Z), "{}", env.to_world);
    }

    #[test]
    fn bad_envmaps_are_located() {
        let dir = TempDir::new("mitsuba-envmap-bad");
        std::fs::create_dir_all(dir.0.join("maps")).unwrap();
        write_float_image(&dir, "maps/sky.exr", |_, _| [1.0; 3]);
        texture::write_png(&dir.0.join("maps/one.png"), 1, 1, &[10, 20, 30]);
        let err = |body: &str| format!("{:#}", load_in(&dir, body, &[]).unwrap_err());
        // (body, line, element, what is said)
        let cases: &[(&str, usize, &str, &str)] = &[
            (
                "<emitter type=\"envmap\">\n<string name=\"filename\" value=\"maps/none.exr\"/></emitter>",
                12,
                r#"<emitter type="envmap">"#,
                "maps/none.exr: cannot read the image",
            ),
            (
                "<emitter type=\"envmap\">\n<string name=\"filename\" value=\"maps/one.png\"/></emitter>",
                13,
                r#"<string name="filename">"#,
                "emitter[0].filename: ",
            ),
            (
                "<emitter type=\"envmap\"><string name=\"filename\" value=\"maps/sky.exr\"/>\n\
                 <transform name=\"to_world\"><scale value=\"2\"/></transform></emitter>",
                13,
                r#"<transform name="to_world">"#,
                r#"the to_world of <emitter type="envmap"> scales or shears"#,
            ),
            (
                "<emitter type=\"envmap\"><string name=\"filename\" value=\"maps/sky.exr\"/>\n\
                 <float name=\"scale\" value=\"-1\"/></emitter>",
                13,
                r#"<float name="scale">"#,
                "emitter[0].scale: every component must be finite and >= 0",
            ),
            (
                "<emitter type=\"envmap\"><string name=\"filename\" value=\"maps/sky.exr\"/>\n\
                 <rgb name=\"scale\" value=\"1, 2, 3\"/></emitter>",
                13,
                r#"<rgb name="scale">"#,
                "expected a <float> or <integer> here",
            ),
            (
                "<emitter type=\"envmap\"><string name=\"filename\" value=\"maps/sky.exr\"/>\n\
                 <boolean name=\"flip\" value=\"true\"/></emitter>",
                13,
                r#"<boolean name="flip">"#,
                "parameter not read by ppm-vk for <emitter type=\"envmap\">",
            ),
        ];
        for (body, line, element, says) in cases {
            let e = err(body);
            assert!(
                e.contains(&format!("scene.xml:{line}:")),
                "{e} should be at line {line}"
            );
            assert!(e.contains(element), "{e} should name {element}");
            assert!(e.contains(says), "{e} should say {says}");
        }
        assert!(err(cases[1].0).contains("1 x 1 with 1 pixels: an environment map needs at least 2 x 2"));
    }

    #[test]
    fn bad_lights_are_located() {
        // (body, line, element, what is said); the body starts on line 12.
        let cases: &[(&str, usize, &str, &str)] = &[
            (
                "<emitter type=\"point\">\n<rgb name=\"intensity\" value=\"1, -1, 1\"/></emitter>",
                13,
                r#"<rgb name="intensity">"#,
                "emitter[0].intensity: every component must be finite and >= 0, got [1, -1, 1]",
            ),
            (
                "<emitter type=\"spot\"><float name=\"cutoff_angle\" value=\"20\"/>\n<float name=\"beam_width\" value=\"30\"/></emitter>",
                13,
                r#"<float name="beam_width">"#,
                "emitter[0].beam_width: must be in (0, cutoff_angle = 20] degrees, got 30",
            ),
            (
                "<emitter type=\"spot\">\n<float name=\"cutoff_angle\" value=\"100\"/></emitter>",
                13,
                r#"<float name="cutoff_angle">"#,
                "emitter[0].cutoff_angle: must be in (0, 90] degrees",
            ),
            (
                "<emitter type=\"spot\">\n<transform name=\"to_world\"><scale z=\"2\"/></transform></emitter>",
                13,
                r#"<transform name="to_world">"#,
                "a spot's cone must stay round",
            ),
            (
                "<emitter type=\"spot\">\n<texture name=\"texture\" type=\"bitmap\"/></emitter>",
                13,
                r#"<texture type="bitmap" name="texture">"#,
                "projected texture is not supported",
            ),
            (
                "<emitter type=\"point\"><point name=\"position\" value=\"1\"/>\n<transform name=\"to_world\"/></emitter>",
                13,
                r#"<transform name="to_world">"#,
                "has both position and to_world",
            ),
            (
                "<emitter type=\"directional\"><vector name=\"direction\" value=\"1\"/>\n<transform name=\"to_world\"/></emitter>",
                13,
                r#"<transform name="to_world">"#,
                "has both direction and to_world",
            ),
            (
                "<emitter type=\"directional\">\n<vector name=\"direction\" value=\"0\"/></emitter>",
                13,
                r#"<vector name="direction">"#,
                "the direction of <emitter type=\"directional\"> is zero",
            ),
            (
                "<emitter type=\"directional\">\n<float name=\"irradiance\" value=\"-2\"/></emitter>",
                13,
                r#"<float name="irradiance">"#,
                "emitter[0].irradiance",
            ),
            (
                "<emitter type=\"constant\">\n<transform name=\"to_world\"><scale x=\"-1\" y=\"3\"/></transform></emitter>",
                13,
                r#"<transform name="to_world">"#,
                r#"the to_world of <emitter type="constant"> scales or shears"#,
            ),
            (
                "<emitter type=\"constant\">\n<float name=\"radiance\" value=\"nan\"/></emitter>",
                13,
                r#"<float name="radiance">"#,
                "not finite",
            ),
            (
                "<emitter type=\"point\">\n<float name=\"power\" value=\"1\"/></emitter>",
                13,
                r#"<float name="power">"#,
                "parameter not read by ppm-vk for <emitter type=\"point\">",
            ),
            (
                "<emitter type=\"point\">\n<bsdf type=\"diffuse\"/></emitter>",
                13,
                r#"<bsdf type="diffuse">"#,
                "not expected inside <emitter type=\"point\">",
            ),
            (
                "<emitter type=\"area\"/>",
                12,
                r#"<emitter type="area">"#,
                "an area emitter belongs inside a shape",
            ),
        ];
        for (body, line, element, says) in cases {
            let e = error(body);
            assert!(
                e.contains(&format!("scene.xml:{line}:")),
                "{e} should be at line {line}"
            );
            assert!(e.contains(element), "{e} should name {element}");
            assert!(e.contains(says), "{e} should say {says}");
        }
    }

    #[test]
    fn lights_alone_light_a_scene_and_keep_file_order() {
        // Without the head's rectangle: a scene lit by these lights only validates.
        let dir = TempDir::new("mitsuba-lights-only");
        let path = dir.write(
            "only.xml",
            r#"<scene version="3.0.0">
    <sensor type="perspective"><float name="fov" value="40"/>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>
    <emitter type="spot"/>
    <shape type="rectangle"/>
    <emitter type="point"><rgb name="intensity" value="0"/></emitter>
    <emitter type="directional"/>
</scene>"#,
        );
        let s = super::super::load(&path, &[]).unwrap_or_else(|e| panic!("{e:#}"));
        let kinds: Vec<&str> = s.emitters.iter().map(Emitter::kind).collect();
        assert_eq!(kinds, ["spot", "point", "directional"]);
    }

    #[test]
    fn area_emitters_on_every_shape() {
        let dir = TempDir::new("mitsuba-area");
        dir.write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
        dir.write(
            "tri.ply",
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
             element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
        );
        for shape in ["rectangle", "cube", "disk", "sphere", "obj", "ply"] {
            let file = match shape {
                "obj" | "ply" => format!(r#"<string name="filename" value="tri.{shape}"/>"#),
                _ => String::new(),
            };
            let s = load_in(
                &dir,
                &format!(
                    r#"<shape type="{shape}">{file}<bsdf type="diffuse"/><emitter type="area"><rgb name="radiance" value="2, 3, 4"/><float name="sampling_weight" value="3"/></emitter></shape>"#
                ),
                &[],
            )
            .unwrap_or_else(|e| panic!("{shape}: {e:#}"));
            let material = match shape {
                "rectangle" | "cube" | "disk" => s.quads.last().unwrap().material,
                "sphere" => s.spheres[0].material,
                _ => s.meshes[0].materials[0],
            };
            let m = &s.materials[material as usize];
            assert_eq!(m.emission, Vec3::new(2.0, 3.0, 4.0), "{shape}");
            assert!(m.is_light(), "{shape}");
        }
        let e = error(r#"<shape type="sphere"><emitter type="area"/><emitter type="area"/></shape>"#);
        assert!(e.contains("a second emitter"), "{e}");
    }

    /// A texture on an area emitter's radiance (Mitsuba 3's src/emitters/area.cpp): read on rectangles and
    /// meshes (an EXR's values above 1 kept: radiances are unbounded), Material::emission its largest value,
    /// mirrored like a bsdf's texture on a turned rectangle; refused on spheres and for negative values.
    #[test]
    fn textured_radiance_on_rectangles_and_meshes() {
        let dir = TempDir::new("mitsuba-area-texture");
        write_float_image(&dir, "glow.exr", |x, y| [x as f32 * 5.0, 2.0, y as f32 + 0.5]);
        let emitter = r#"<emitter type="area"><texture type="bitmap" name="radiance">
              <string name="filename" value="glow.exr"/></texture></emitter>"#;
        let s = load_in(
            &dir,
            &format!(
                r#"<shape type="rectangle"><bsdf type="diffuse"/>{emitter}</shape>
                   <texture type="bitmap" id="t"><string name="filename" value="glow.exr"/></texture>
                   <shape type="rectangle"><boolean name="flip_normals" value="true"/>
                     <emitter type="area"><ref name="radiance" id="t"/></emitter></shape>"#
            ),
            &[],
        )
        .unwrap_or_else(|e| panic!("{e:#}"));
        let m = &s.materials[s.quads[1].material as usize]; // quads[0]: the lamp of the test head
        let t = &s.textures[m.emission_texture.expect("a radiance texture") as usize];
        assert_eq!(m.emission, Vec3::new(15.0, 2.0, 1.5));
        assert_eq!((m.emission, t.to_uv), (t.max(), texture::IDENTITY_UV));
        assert!(m.texture.is_none() && m.is_light());
        // The flipped one runs its first edge backwards: its texture reads (1 - u, v).
        let turned = &s.materials[s.quads[2].material as usize];
        let t = &s.textures[turned.emission_texture.unwrap() as usize];
        assert_eq!(t.to_uv, [-1.0, 0.0, 1.0, 0.0, 1.0, 0.0]);
        // Meshes (with texture coordinates) read it too; spheres are refused by name.
        for shape in ["cube", "disk", "cylinder"] {
            let s = load_in(&dir, &format!(r#"<shape type="{shape}">{emitter}</shape>"#), &[])
                .unwrap_or_else(|e| panic!("{shape}: {e:#}"));
            let m = &s.materials[s.meshes[0].materials[0] as usize];
            assert!(m.emission_texture.is_some() && s.meshes[0].uvs.is_some(), "{shape}");
        }
        let e = load_in(&dir, &format!(r#"<shape type="sphere">{emitter}</shape>"#), &[]).unwrap_err();
        let e = format!("{e:#}");
        assert!(
            e.contains("a texture on an area emitter's radiance on a sphere is not supported yet"),
            "{e}"
        );
        write_float_image(&dir, "negative.exr", |x, _| [1.0 - x as f32, 1.0, 1.0]);
        let e = load_in(
            &dir,
            r#"<shape type="rectangle"><emitter type="area"><texture type="bitmap" name="radiance">
                 <string name="filename" value="negative.exr"/></texture></emitter></shape>"#,
            &[],
        )
        .unwrap_err();
        let e = format!("{e:#}");
        assert!(
            e.contains("a radiance must be finite and at least 0") && e.contains("scene.xml:12:"),
            "{e}"
        );
    }
}
