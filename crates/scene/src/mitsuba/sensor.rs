//! The `<sensor>` element (Mitsuba's perspective sensor) as the scene's camera, with its `<film>`
//! (hdrfilm: the image size; its `<rfilter>`) and `<sampler>` (ignored: it only decides the noise of
//! Mitsuba's estimate).

use anyhow::Result;
use glam::{DMat3, DVec3};

use super::elem::Elem;
use super::properties::{number, Props};
use super::Builder;
use crate::Camera;

impl Builder {
    /// The scene's camera from the first `<sensor>` (kept by the document walk); a scene without one is
    /// refused. Called last, as its far clip is compared with the scene's bounds.
    pub(super) fn camera(&mut self) -> Result<()> {
        let Some(e) = self.sensor.take() else {
            return Err(self
                .root
                .err("no <sensor>: give a perspective sensor (ppm-vk has no default camera)"));
        };
        if e.kind() != "perspective" {
            return Err(e.err("only the perspective (pinhole) sensor is supported"));
        }
        let (props, objects) = Props::of(&e);
        let mut size = (768, 576); // hdrfilm's defaults
        let mut film_seen = false;
        for o in objects {
            match (o.tag.as_str(), o.kind()) {
                // Mitsuba 0.6's ldrfilm (tone-mapped 8-bit output) and tiledhdrfilm: the same image before
                // its encoding, which is warned about (ppm-vk writes linear HDR).
                ("film", "hdrfilm" | "ldrfilm" | "tiledhdrfilm") => {
                    film_seen = true;
                    size = self.film(o)?;
                }
                ("film", _) => return Err(o.err("only hdrfilm is supported")),
                // The sampler decides only the noise of Mitsuba's estimate; ppm-vk's --seed is its own.
                // Mitsuba 0.6's quasi-random samplers, which Mitsuba 3 dropped: said, as Mitsuba 3 would refuse them.
                ("sampler", kind @ ("halton" | "hammersley" | "sobol")) => self.warn(
                    o,
                    format!("Mitsuba 3 has no {kind} sampler (Mitsuba 0.6's): ignored, as every sampler"),
                ),
                ("sampler", _) => {}
                ("ref", _) if o.attr("id").is_some_and(|id| self.samplers.iter().any(|s| s == id)) => {}
                _ => return Err(o.err(format!("not expected inside {}", e.what()))),
            }
        }
        if !film_seen {
            self.warn(
                &e,
                "no film: hdrfilm's defaults (768 x 576, gaussian filter) apply; rendered with a box filter",
            );
        }
        let aspect = f64::from(size.0) / f64::from(size.1);
        let x_fov = fov_x(&props, aspect, &e)?;
        let m = props.transform("to_world")?;
        for name in ["principal_point_offset_x", "principal_point_offset_y"] {
            if props.float(name)?.is_some_and(|v| v != 0.0) {
                return Err(props
                    .get(name)
                    .unwrap()
                    .err("an off-centre principal point is not supported"));
            }
        }
        // shutter_open_time is Mitsuba 0.6's name: motion blur is not read either way.
        // focus_distance: every projective camera of Mitsuba 3 reads it; a pinhole's image does not use it.
        props.ignore(&[
            "near_clip",
            "shutter_open",
            "shutter_close",
            "shutter_open_time",
            "focus_distance",
        ]);
        let far = props.float("far_clip")?;
        props.finish()?;
        let l = m.matrix3;
        if (l.transpose() * l - DMat3::IDENTITY)
            .to_cols_array()
            .iter()
            .any(|x| x.abs() > 1e-4)
        {
            return Err(e.err("to_world of the sensor has a scale or shear (Mitsuba refuses scale factors too)"));
        }
        if l.determinant() < 0.0 {
            return Err(e.err("to_world of the sensor mirrors the image: not supported"));
        }
        let eye = m.translation;
        let vfov = 2.0 * ((0.5 * x_fov.to_radians()).tan() / aspect).atan();
        self.scene.camera = Camera {
            eye: eye.as_vec3(),
            look_at: (eye + l.z_axis).as_vec3(),
            up: l.y_axis.as_vec3(),
            vfov_deg: vfov.to_degrees() as f32,
            width: size.0,
            height: size.1,
        };
        self.origins.insert("camera".into(), e.clone());
        if let Some(far) = far {
            let (lo, hi) = self.scene.bounds();
            let farthest = (0..8)
                .map(|k| {
                    let c = DVec3::new(
                        if k & 1 == 0 { lo.x } else { hi.x } as f64,
                        if k & 2 == 0 { lo.y } else { hi.y } as f64,
                        if k & 4 == 0 { lo.z } else { hi.z } as f64,
                    );
                    (c - eye).length()
                })
                .fold(0.0, f64::max);
            if far < farthest {
                self.warn(
                    &e,
                    format!("far_clip {far} ignored: ppm-vk renders the scene out to {farthest:.3}"),
                );
            }
        }
        Ok(())
    }

    fn film(&mut self, o: &Elem) -> Result<(u32, u32)> {
        let (fp, rest) = Props::of(o);
        let size = |name: &str, default: u32| -> Result<u32> {
            match fp.float(name)? {
                None => Ok(default),
                Some(v) if v >= 1.0 && v.fract() == 0.0 && v <= f64::from(u32::MAX) => Ok(v as u32),
                Some(v) => Err(fp
                    .get(name)
                    .unwrap()
                    .err(format!("must be a positive integer, got {v}"))),
            }
        };
        let size = (size("width", 768)?, size("height", 576)?);
        for name in ["crop_offset_x", "crop_offset_y", "crop_width", "crop_height"] {
            if let Some(p) = fp.get(name) {
                return Err(p.err("a crop window is not supported"));
            }
        }
        // Mitsuba 0.6's film parameters that Mitsuba 3 dropped: its ldrfilm's tone mapping, the log and
        // the banner. Ignored with a warning: ppm-vk's image is the linear one before them.
        let dropped: Vec<&str> = [
            "tonemap_method",
            "gamma",
            "exposure",
            "key",
            "burn",
            "attach_log",
            "banner",
            "high_quality_edges",
        ]
        .into_iter()
        .filter(|n| fp.get(n).is_some() && (o.kind() != "hdrfilm" || !matches!(*n, "banner" | "high_quality_edges")))
        .collect();
        if o.kind() != "hdrfilm" || !dropped.is_empty() {
            self.warn(
                o,
                format!(
                    "a Mitsuba 0.6 film{}: ppm-vk writes the linear image, without tone mapping{}",
                    if o.kind() == "hdrfilm" { " parameter" } else { "" },
                    if dropped.is_empty() {
                        String::new()
                    } else {
                        format!(" (ignored: {})", dropped.join(", "))
                    }
                ),
            );
        }
        // Output encoding only: the image is the same.
        fp.ignore(&[
            "pixel_format",
            "component_format",
            "file_format",
            "banner",
            "high_quality_edges",
            "sample_border",
            "compensate",
        ]);
        fp.finish()?;
        match rest[..] {
            [] => self.warn(
                o,
                "no rfilter: Mitsuba's default is gaussian; ppm-vk renders with a box filter",
            ),
            [r] if r.tag == "rfilter" && r.kind() == "box" => {}
            [r] if r.tag == "rfilter" => self.warn(r, "ppm-vk renders with a box filter"),
            _ => return Err(rest[0].err(format!("not expected inside {}", o.what()))),
        }
        Ok(size)
    }
}

/// `fov` (with `fov_axis`) or `focal_length` as the horizontal field of view in degrees, as
/// Mitsuba's `parse_fov`.
fn fov_x(props: &Props, aspect: f64, e: &Elem) -> Result<f64> {
    let (fov, axis) = match (props.float("fov")?, props.string("focal_length")?) {
        (Some(_), Some(_)) => return Err(e.err("give either fov or focal_length, not both")),
        (Some(fov), None) => {
            let axis = props.string("fov_axis")?.unwrap_or("x").to_ascii_lowercase();
            let axis = match axis.as_str() {
                "smaller" => if aspect > 1.0 { "y" } else { "x" }.to_string(),
                "larger" => if aspect > 1.0 { "x" } else { "y" }.to_string(),
                _ => axis,
            };
            (fov, axis)
        }
        (None, focal) => {
            let f = focal.unwrap_or("50mm");
            let mm = number(e, f.strip_suffix("mm").unwrap_or(f))?;
            // The diagonal of a 36 x 24 mm frame.
            (
                (36f64.hypot(24.0) / (2.0 * mm)).atan().to_degrees() * 2.0,
                "diagonal".to_string(),
            )
        }
    };
    if !(fov > 0.0 && fov < 180.0) {
        return Err(e.err(format!("fov must be in (0, 180) degrees, got {fov}")));
    }
    let half = (0.5 * fov.to_radians()).tan();
    let x = match axis.as_str() {
        "x" => fov,
        "y" => (2.0 * (half * aspect).atan()).to_degrees(),
        "diagonal" => (2.0 * (half / (1.0 + 1.0 / (aspect * aspect)).sqrt()).atan()).to_degrees(),
        other => {
            return Err(e.err(format!(
                "fov_axis \"{other}\": expected x, y, diagonal, smaller or larger"
            )))
        }
    };
    Ok(x)
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::super::load;
    use super::*;
    use crate::TempDir;

    fn camera(sensor_body: &str, film: &str) -> Result<Camera> {
        let dir = TempDir::new("mitsuba-cam");
        let path = dir.write(
            "cam.xml",
            &format!(
                r#"<scene version="3.0.0"><sensor type="perspective">{sensor_body}
                   <film type="hdrfilm">{film}<rfilter type="box"/></film></sensor>
                   <shape type="rectangle"><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape></scene>"#
            ),
        );
        load(&path, &[]).map(|s| s.camera)
    }

    #[test]
    fn camera_lookat_and_fov_axes_match_the_toml_camera() {
        let look =
            r#"<transform name="to_world"><lookat origin="0, 1, 2.9" target="0, 0.8, 0" up="0, 1, 0"/></transform>"#;
        let c = camera(
            &format!(r#"<float name="fov" value="50"/><string name="fov_axis" value="y"/>{look}"#),
            "",
        )
        .unwrap();
        assert_eq!((c.width, c.height), (768, 576));
        assert!((c.vfov_deg - 50.0).abs() < 1e-4, "{c:?}");
        assert!(c.eye.distance(Vec3::new(0.0, 1.0, 2.9)) < 1e-6);
        let dir = (c.look_at - c.eye).normalize();
        assert!(dir.distance(Vec3::new(0.0, -0.2, -2.9).normalize()) < 1e-6);
        // up is orthogonalised by Mitsuba's lookat; it spans the same plane with dir as (0, 1, 0).
        assert!(c.up.cross(dir).normalize().distance(Vec3::Y.cross(dir).normalize()) < 1e-6);

        // Horizontal fov 60 on a 2:1 image: vertical 2 atan(tan 30 / 2).
        let want = 2.0 * ((30f64.to_radians().tan()) / 2.0).atan().to_degrees();
        let film = r#"<integer name="width" value="200"/><integer name="height" value="100"/>"#;
        for (axis, fov) in [
            ("x", 60.0),
            ("larger", 60.0),
            ("y", want),
            ("smaller", want),
            (
                "diagonal",
                2.0 * (30f64.to_radians().tan() * (1.0 + 0.25f64).sqrt()).atan().to_degrees(),
            ),
        ] {
            let c = camera(
                &format!(r#"<float name="fov" value="{fov}"/><string name="fov_axis" value="{axis}"/>{look}"#),
                film,
            )
            .unwrap();
            assert!(
                (f64::from(c.vfov_deg) - want).abs() < 1e-4,
                "{axis}: {} vs {want}",
                c.vfov_deg
            );
        }
        // focal_length: 50mm by default, on the diagonal of a 36 x 24 mm frame.
        let c = camera(look, film).unwrap();
        let diag = 2.0 * (36f64.hypot(24.0) / 100.0).atan();
        let half_w = (0.5 * diag).tan() / (1.0 + 0.25f64).sqrt();
        assert!((f64::from(c.vfov_deg) - (2.0 * (half_w / 2.0).atan()).to_degrees()).abs() < 1e-4);

        // The same camera by rotate + translate: looking down -z from (0, 0, 3) is a 180 degree turn.
        let c = camera(r#"<float name="fov" value="40"/><transform name="to_world"><rotate y="1" angle="180"/><translate z="3"/></transform>"#, "").unwrap();
        assert!(
            c.eye.distance(Vec3::new(0.0, 0.0, 3.0)) < 1e-6
                && (c.look_at - c.eye).normalize().distance(Vec3::NEG_Z) < 1e-6
        );
        assert!(c.up.distance(Vec3::Y) < 1e-6);

        let e = format!(
            "{:#}",
            camera(
                r#"<float name="fov" value="40"/><transform name="to_world"><scale x="-1"/></transform>"#,
                ""
            )
            .unwrap_err()
        );
        assert!(
            e.contains("mirrors the image") && e.contains("<sensor type=\"perspective\">"),
            "{e}"
        );
        let e = format!(
            "{:#}",
            camera(
                r#"<float name="fov" value="40"/><transform name="to_world"><scale value="2"/></transform>"#,
                ""
            )
            .unwrap_err()
        );
        assert!(e.contains("scale"), "{e}");
    }

    #[test]
    fn samplers_are_ignored_and_0_6_ones_said() {
        let dir = TempDir::new("mitsuba-sampler");
        for (kind, warned) in [
            ("independent", false),
            ("ldsampler", false),
            ("halton", true),
            ("sobol", true),
        ] {
            let path = dir.write(
                "s.xml",
                &format!(
                    r#"<scene version="3.0.0"><sensor type="perspective"><sampler type="{kind}"><integer name="sample_count" value="4"/></sampler>
                       <film type="hdrfilm"><rfilter type="box"/></film></sensor>
                       <shape type="sphere"><emitter type="area"/></shape></scene>"#
                ),
            );
            let s = load(&path, &[]).unwrap();
            let said = s
                .warnings
                .iter()
                .any(|w| w.contains(&format!("Mitsuba 3 has no {kind} sampler")));
            assert_eq!(said, warned, "{kind}: {:?}", s.warnings);
        }
    }
}
