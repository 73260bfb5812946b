//! The `<bsdf>` element: one reader per Mitsuba plugin (diffuse, twosided, conductor, roughconductor,
//! dielectric, roughdielectric, thindielectric, plastic and roughplastic), called from the dispatch in
//! [`Builder::bsdf`]; the parameters they share (indices of refraction, microfacet distributions,
//! diffuse reflectances); and the scene material a shape's bsdf becomes.

use std::rc::Rc;

use anyhow::Result;
use glam::Vec3;

use super::elem::Elem;
use super::properties::{color, number, Props};
use super::texture::{same_texture, Tex};
use super::Builder;
use crate::texture::{self, Pattern};
use crate::{conductors, Material, Microfacet, Surface};

/// A bsdf's bump or normal map as read (modifiers.rs): the texture, and a bump map's scale (`None`: a
/// normal map).
#[derive(Clone, Debug)]
pub(super) struct Perturbation {
    pub(super) texture: Rc<Tex>,
    pub(super) bump_scale: Option<f32>,
}

/// A mask's opacity as read (mask.rs): a constant, or a texture (Mitsuba's eval_1 of it: for RGB the
/// luminance), both clamped to [0, 1] where they are used, as Mitsuba's `eval_opacity`.
#[derive(Clone, Debug)]
pub(super) enum Opacity {
    Value(f32),
    Texture(Rc<Tex>),
}

/// A BSDF as ppm-vk reads it.
#[derive(Clone, Debug)]
pub(super) struct Bsdf {
    pub(super) surface: Surface,
    /// Wrapped in `twosided` (or, for a dielectric, two-sided by nature).
    pub(super) two_sided: bool,
    pub(super) id: Option<String>,
    /// The texture its diffuse reflectance is read from (the surface's constant is then the texture's
    /// largest value in each channel).
    pub(super) texture: Option<Rc<Tex>>,
    /// A `bumpmap` or `normalmap` around it.
    pub(super) normal_map: Option<Perturbation>,
    /// A `blendbsdf`: its weight and components (blend.rs); `surface` is then a `Surface::Blend` whose
    /// indices [`Builder::material`] sets, `texture` and `normal_map` are `None`.
    pub(super) blend: Option<Rc<Blend>>,
    /// A `mask` around it (or a `null` bsdf): mask.rs.
    pub(super) opacity: Option<Opacity>,
    /// The texture its specular_reflectance is read from (conductors, thin dielectrics; the surface's
    /// constant is then the texture's largest value in each channel).
    pub(super) specular: Option<Rc<Tex>>,
    /// The texture its (isotropic) roughness alpha is read from (roughconductor, roughdielectric; the
    /// surface's alpha is then the luminance of the texture's largest values).
    pub(super) alpha: Option<Rc<Tex>>,
}

/// A `blendbsdf` as read (blend.rs): its weight (a constant, or the luminance of `texture`) and its two components.
#[derive(Debug)]
pub(super) struct Blend {
    pub(super) weight: f32,
    pub(super) texture: Option<Rc<Tex>>,
    pub(super) first: Bsdf,
    pub(super) second: Bsdf,
}

impl Bsdf {
    /// This bsdf with `f` applied to each of its textures (a rectangle turned around: shape.rs).
    pub(super) fn map_textures(&self, f: impl Fn(&Tex) -> Tex) -> Bsdf {
        let map = |t: &Option<Rc<Tex>>| t.as_ref().map(|t| Rc::new(f(t)));
        Bsdf {
            texture: map(&self.texture),
            specular: map(&self.specular),
            alpha: map(&self.alpha),
            opacity: match &self.opacity {
                Some(Opacity::Texture(t)) => Some(Opacity::Texture(Rc::new(f(t)))),
                o => o.clone(),
            },
            ..self.clone()
        }
    }
}

/// Indices of the refraction of Mitsuba's named materials (`int_ior="bk7"`), from its documentation.
const IOR_TABLE: &[(&str, f64)] = &[
    ("vacuum", 1.0),
    ("helium", 1.000036),
    ("hydrogen", 1.000132),
    ("air", 1.000277),
    ("carbon dioxide", 1.00045),
    ("water", 1.3330),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.470),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.5750),
    ("diamond", 2.419),
];

impl Builder {
    /// A `<bsdf>`: the checks every plugin shares, then its plugin's reader (which returns it without
    /// its id); every property must have been read by then.
    pub(super) fn bsdf(&mut self, e: &Elem) -> Result<Bsdf> {
        let (props, objects) = Props::of(e);
        let id = e.attr("id").map(str::to_string);
        let nested: Vec<&Elem> = objects.iter().copied().filter(|c| c.tag == "bsdf").collect();
        // A bump or normal map also holds textures (and refs to them or to its bsdf): modifiers.rs.
        let modifier = matches!(e.kind(), "bumpmap" | "normalmap" | "blendbsdf" | "mask");
        if let Some(o) = objects.iter().find(|c| c.tag != "bsdf" && !modifier) {
            return Err(o.err(format!("not expected inside {}", e.what())));
        }
        if e.kind() != "twosided" && !modifier {
            if let Some(n) = nested.first() {
                return Err(n.err(format!("a bsdf nested in {} is not supported", e.what())));
            }
        }
        let bsdf = match e.kind() {
            "diffuse" => self.diffuse(&props)?,
            "twosided" => self.twosided(e, &nested)?,
            "conductor" => self.conductor(e, &props)?,
            "roughconductor" => self.rough_conductor(e, &props)?,
            "dielectric" => dielectric(e, &props)?,
            "roughdielectric" => self.rough_dielectric(e, &props)?,
            "thindielectric" => self.thin_dielectric(e, &props)?,
            "plastic" => self.plastic(e, &props, false)?,
            "roughplastic" => self.plastic(e, &props, true)?,
            "bumpmap" => self.bumpmap(e, &props, &objects)?,
            "normalmap" => self.normalmap(e, &props, &objects)?,
            "blendbsdf" => self.blendbsdf(e, &props, &objects)?,
            "mask" => self.mask(e, &props, &objects)?,
            "null" => self.null(),
            _ => {
                return Err(e.err(
                    "unsupported bsdf (read: diffuse, twosided, conductor, roughconductor, \
                     dielectric, roughdielectric, thindielectric, plastic, roughplastic, bumpmap, normalmap, \
                     blendbsdf, mask, null)",
                ))
            }
        };
        props.finish()?;
        Ok(Bsdf { id, ..bsdf })
    }

    /// Mitsuba's `diffuse`: its reflectance a colour or a texture.
    fn diffuse(&self, props: &Props) -> Result<Bsdf> {
        let (albedo, texture) = self.reflectance(props, "reflectance")?;
        Ok(Bsdf {
            surface: Surface::Diffuse { albedo },
            two_sided: false,
            id: None,
            texture,
            normal_map: None,
            blend: None,
            opacity: None,
            specular: None,
            alpha: None,
        })
    }

    /// Mitsuba's `twosided`: its nested bsdf (or two the same) on both sides.
    fn twosided(&mut self, e: &Elem, nested: &[&Elem]) -> Result<Bsdf> {
        let inner = match nested[..] {
            [one] => self.bsdf(one)?,
            [a, b] => {
                let (x, y) = (self.bsdf(a)?, self.bsdf(b)?);
                if x.blend.is_some() || y.blend.is_some() {
                    return Err(b.err("two bsdfs in a twosided, one a blendbsdf: not supported (give one)"));
                }
                let same_map = match (&x.normal_map, &y.normal_map) {
                    (None, None) => true,
                    (Some(a), Some(b)) => {
                        a.bump_scale == b.bump_scale && same_texture(&Some(a.texture.clone()), &Some(b.texture.clone()))
                    }
                    _ => false,
                };
                if x.opacity.is_some() || y.opacity.is_some() {
                    return Err(b.err("a mask or null bsdf in a twosided of two bsdfs is not supported"));
                }
                if x.surface != y.surface
                    || !same_texture(&x.texture, &y.texture)
                    || !same_texture(&x.specular, &y.specular)
                    || !same_texture(&x.alpha, &y.alpha)
                    || !same_map
                {
                    return Err(b.err(
                        "a different bsdf on the back side is not supported (ppm-vk \
                         surfaces are the same on both sides)",
                    ));
                }
                x
            }
            _ => return Err(e.err("needs one nested bsdf")),
        };
        if inner.two_sided || matches!(inner.surface, Surface::Glass { .. }) {
            return Err(e.err("wraps a two-sided bsdf (Mitsuba refuses this too)"));
        }
        // A blend's components: Mitsuba's twosided refuses a transmitting component (its flags are the
        // union of theirs); a twosided one is already two-sided.
        if inner.blend.is_some() && inner.leaves().iter().any(|l| l.two_sided) {
            return Err(e.err(
                "wraps a blendbsdf with a two-sided or transmitting component (a dielectric, or one already \
                 in twosided): not supported (Mitsuba refuses a transmitting one)",
            ));
        }
        Ok(Bsdf {
            two_sided: true,
            ..inner
        })
    }

    /// Mitsuba's `plastic` and, with `rough_coat`, `roughplastic` (its coat's isotropic microfacet
    /// distribution, read after the reflectances): a diffuse base under a dielectric coat.
    fn plastic(&mut self, e: &Elem, props: &Props, rough_coat: bool) -> Result<Bsdf> {
        let (int, ext) = (
            ior(e, props, "int_ior", "polypropylene")?,
            ior(e, props, "ext_ior", "air")?,
        );
        let (mut diffuse, mut texture) = self.reflectance(props, "diffuse_reflectance")?;
        if let Some(p) = props
            .get("specular_reflectance")
            .filter(|p| matches!(p.tag.as_str(), "texture" | "ref"))
        {
            return Err(p.err(format!(
                "a texture on {}'s specular_reflectance is not supported yet (its diffuse lobe's bound \
                 depends on it)",
                e.kind()
            )));
        }
        if let Some(p) = props
            .get("alpha")
            .filter(|p| matches!(p.tag.as_str(), "texture" | "ref"))
        {
            return Err(p.err(
                "a texture on roughplastic's alpha is not supported (Mitsuba 3 reads it as a float, and \
                 ppm-vk's coat table is made per alpha)",
            ));
        }
        let specular = props.color("specular_reflectance")?.unwrap_or(Vec3::ONE);
        let nonlinear = props.boolean("nonlinear")?;
        let rough = if rough_coat {
            let rough = microfacet(e, props)?;
            if rough.is_anisotropic() {
                return Err(e.err("roughplastic is isotropic (Mitsuba reads alpha only): give alpha"));
            }
            Some(rough)
        } else {
            None
        };
        // A texture above the photons' bound is lowered per pixel, as Surface::plastic lowers a
        // constant (which then stays within it).
        let coat = self.coats.coat((int / ext) as f32, rough);
        let most = crate::plastic::max_diffuse_reflectance((int / ext) as f32, nonlinear, coat);
        if let Some(t) = &texture {
            if let Some((lowered, n)) = t.texture.lowered(most) {
                let what = match lowered.pattern {
                    Pattern::Bitmap { .. } => "pixels",
                    Pattern::Checkerboard { .. } => "colours",
                };
                self.warn(
                    e,
                    format!(
                        "diffuse_reflectance texture \"{}\": {n} {what} lowered to at most {most:.4} per \
                         channel: above it a photon's diffuse bounce off this coat (index {}) would gain \
                         flux (docs/scene-format.md, plastic)",
                        t.texture.name,
                        (int / ext) as f32
                    ),
                );
                diffuse = lowered.max();
                texture = Some(Rc::new(Tex {
                    texture: lowered,
                    at: t.at.clone(),
                }));
            }
        }
        let (surface, lowered) =
            Surface::plastic_in(diffuse, specular, (int / ext) as f32, nonlinear, rough, &mut self.coats);
        if let Some(message) = lowered {
            self.warn(e, message);
        }
        Ok(Bsdf {
            surface,
            two_sided: false,
            id: None,
            texture,
            normal_map: None,
            blend: None,
            opacity: None,
            specular: None,
            alpha: None,
        })
    }

    /// A diffuse reflectance parameter (`reflectance`, `diffuse_reflectance`; Mitsuba's default 0.5): a
    /// colour, or a texture (nested, or a `ref` to a top-level one) whose values are reflectances, with
    /// its largest value in each channel.
    fn reflectance(&self, props: &Props, name: &str) -> Result<(Vec3, Option<Rc<Tex>>)> {
        let Some(p) = props.get(name) else {
            return Ok((Vec3::splat(0.5), None));
        };
        let t = match p.tag.as_str() {
            "texture" => Rc::new(self.texture(p)?),
            "ref" => {
                let id = p.required("id")?;
                self.textures.get(id).cloned().ok_or_else(|| {
                    let mut known: Vec<&str> = self.textures.keys().map(String::as_str).collect();
                    known.sort();
                    let known = if known.is_empty() {
                        "none".to_string()
                    } else {
                        known.join(", ")
                    };
                    p.err(format!(
                        "no texture with id \"{id}\" defined before it (known: {known})"
                    ))
                })?
            }
            _ => return Ok((color(p)?, None)),
        };
        if let Some(bad) = t.texture.out_of_range() {
            return Err(t.at.err(format!(
                "{}: {bad}: a reflectance texture's values must be in [0, 1]",
                t.texture.name
            )));
        }
        Ok((t.texture.max(), Some(t)))
    }

    /// Index of the scene material for `bsdf` with `emission`, named `name` (made on first use; the
    /// same name for different contents gets a suffix).
    pub(super) fn material(
        &mut self,
        name: &str,
        bsdf: &Bsdf,
        emission: Vec3,
        radiance: Option<&(texture::Texture, Elem)>,
        e: &Elem,
    ) -> u32 {
        // A blend: its components' materials first (named by their ids, else after it), then the blend of
        // them, whose texture is its weight's.
        let (surface, weight_texture) = match &bsdf.blend {
            Some(b) => {
                let part = |p: &Bsdf, k: u32| p.id.clone().unwrap_or_else(|| format!("{name}.{k}"));
                let first = self.material(&part(&b.first, 0), &b.first, Vec3::ZERO, None, e);
                let second = self.material(&part(&b.second, 1), &b.second, Vec3::ZERO, None, e);
                let surface = Surface::Blend {
                    weight: b.weight,
                    first,
                    second,
                };
                (surface, b.texture.as_ref())
            }
            None => (bsdf.surface, bsdf.texture.as_ref()),
        };
        let texture =
            weight_texture.map(|t| texture::intern(&mut self.scene.textures, std::borrow::Cow::Borrowed(&t.texture)));
        let emission_texture =
            radiance.map(|(t, _)| texture::intern(&mut self.scene.textures, std::borrow::Cow::Borrowed(t)));
        let normal_map = bsdf.normal_map.as_ref().map(|p| {
            let texture = texture::intern(&mut self.scene.textures, std::borrow::Cow::Borrowed(&p.texture.texture));
            match p.bump_scale {
                Some(scale) => crate::NormalMap::Bump { texture, scale },
                None => crate::NormalMap::Normal { texture },
            }
        });
        let opacity = bsdf.opacity.as_ref().map(|o| {
            let t = match o {
                Opacity::Texture(t) => std::borrow::Cow::Borrowed(&t.texture),
                // A constant is a texture of one value (a checkerboard of two equal colours: no pixels).
                Opacity::Value(v) => std::borrow::Cow::Owned(texture::Texture {
                    name: format!("opacity {v}"),
                    pattern: Pattern::Checkerboard {
                        color0: Vec3::splat(*v),
                        color1: Vec3::splat(*v),
                    },
                    filter: texture::Filter::Bilinear,
                    wrap: texture::Wrap::Repeat,
                    to_uv: texture::IDENTITY_UV,
                }),
            };
            texture::intern(&mut self.scene.textures, t)
        });
        let intern = |scene: &mut crate::Scene, t: &Option<Rc<Tex>>| {
            t.as_ref()
                .map(|t| texture::intern(&mut scene.textures, std::borrow::Cow::Borrowed(&t.texture)))
        };
        let specular_texture = intern(&mut self.scene, &bsdf.specular);
        let alpha_texture = intern(&mut self.scene, &bsdf.alpha);
        let wanted = Material {
            name: name.to_string(),
            surface,
            emission,
            texture,
            normal_map,
            opacity,
            specular_texture,
            alpha_texture,
            emission_texture,
        };
        let mut candidate = name.to_string();
        for n in 2.. {
            match self.scene.materials.iter().position(|m| m.name == candidate) {
                Some(i)
                    if self.scene.materials[i]
                        == Material {
                            name: candidate.clone(),
                            ..wanted.clone()
                        } =>
                {
                    return i as u32
                }
                Some(_) => candidate = format!("{name}#{n}"),
                None => break,
            }
        }
        self.origins.insert(format!("materials.{candidate}"), e.clone());
        if let Some(t) = weight_texture {
            self.origins
                .insert(format!("materials.{candidate}.texture"), t.at.clone());
        }
        for (field, t) in [("specular_texture", &bsdf.specular), ("alpha_texture", &bsdf.alpha)] {
            if let Some(t) = t {
                self.origins
                    .insert(format!("materials.{candidate}.{field}"), t.at.clone());
            }
        }
        if let Some((_, at)) = radiance {
            self.origins
                .insert(format!("materials.{candidate}.emission_texture"), at.clone());
        }
        if let Some(p) = &bsdf.normal_map {
            self.origins
                .insert(format!("materials.{candidate}.normal_map"), p.texture.at.clone());
        }
        self.scene.materials.push(Material {
            name: candidate,
            ..wanted
        });
        (self.scene.materials.len() - 1) as u32
    }
}

/// A bsdf on the front side only, without a texture.
fn one_sided(surface: Surface) -> Bsdf {
    Bsdf {
        surface,
        two_sided: false,
        id: None,
        texture: None,
        normal_map: None,
        blend: None,
        opacity: None,
        specular: None,
        alpha: None,
    }
}

impl Builder {
    /// Mitsuba's `conductor`: a smooth metal.
    fn conductor(&self, e: &Elem, props: &Props) -> Result<Bsdf> {
        let (eta, k) = metal(e, props)?;
        let (reflectance, specular) = self.specular(props)?;
        Ok(Bsdf {
            specular,
            ..one_sided(Surface::conductor(reflectance, eta, k))
        })
    }

    /// Mitsuba's `roughconductor`: a metal with a microfacet distribution.
    fn rough_conductor(&self, e: &Elem, props: &Props) -> Result<Bsdf> {
        let (eta, k) = metal(e, props)?;
        let (reflectance, specular) = self.specular(props)?;
        let (rough, alpha) = self.rough(e, props)?;
        Ok(Bsdf {
            specular,
            alpha,
            ..one_sided(Surface::RoughConductor {
                reflectance,
                eta,
                k,
                rough,
            })
        })
    }

    /// Mitsuba's `roughdielectric`: glass with a microfacet distribution, two-sided by nature.
    fn rough_dielectric(&self, e: &Elem, props: &Props) -> Result<Bsdf> {
        let ior = glass_ior(e, props)?;
        let (rough, alpha) = self.rough(e, props)?;
        Ok(Bsdf {
            surface: Surface::RoughGlass { ior, rough },
            two_sided: true,
            id: None,
            texture: None,
            normal_map: None,
            specular: None,
            alpha,
            blend: None,
            opacity: None,
        })
    }

    /// Mitsuba's `thindielectric`: a thin pane.
    fn thin_dielectric(&self, e: &Elem, props: &Props) -> Result<Bsdf> {
        let (int, ext) = (ior(e, props, "int_ior", "bk7")?, ior(e, props, "ext_ior", "air")?);
        let (reflectance, specular) = self.specular(props)?;
        if let Some(t) = props
            .get("specular_transmittance")
            .filter(|t| matches!(t.tag.as_str(), "texture" | "ref"))
        {
            return Err(t.err(
                "a texture on a thindielectric's specular_transmittance is not supported yet (its \
                 specular_reflectance may be one)",
            ));
        }
        let surface = Surface::ThinDielectric {
            ior: (int / ext) as f32,
            reflectance,
            transmittance: props.color("specular_transmittance")?.unwrap_or(Vec3::ONE),
        };
        // Mitsuba's thin dielectric is the same from both sides.
        Ok(Bsdf {
            surface,
            two_sided: true,
            id: None,
            texture: None,
            normal_map: None,
            specular,
            alpha: None,
            blend: None,
            opacity: None,
        })
    }

    /// A specular_reflectance (Mitsuba's default 1): a colour, or a texture read as a diffuse
    /// reflectance's is (its values refused outside [0, 1]), with its largest value in each channel.
    fn specular(&self, props: &Props) -> Result<(Vec3, Option<Rc<Tex>>)> {
        if props.get("specular_reflectance").is_none() {
            return Ok((Vec3::ONE, None));
        }
        self.reflectance(props, "specular_reflectance")
    }

    /// A rough bsdf's microfacet distribution (`microfacet`), its alpha possibly a texture (nested or a
    /// `ref`): Mitsuba evaluates that with eval_1, the luminance of an RGB texture's value (its
    /// src/textures/bitmap.cpp), floored at 1e-4 at each point. The distribution's alpha is then the
    /// luminance of the texture's largest values (a bound on every point's). A texture on alpha_u or
    /// alpha_v (anisotropic) is refused.
    fn rough(&self, e: &Elem, props: &Props) -> Result<(Microfacet, Option<Rc<Tex>>)> {
        let is_texture = |name: &str| props.get(name).filter(|p| matches!(p.tag.as_str(), "texture" | "ref"));
        for name in ["alpha_u", "alpha_v"] {
            if let Some(p) = is_texture(name) {
                return Err(p.err(format!(
                    "a texture on {name} is not supported yet (an isotropic alpha may be one)"
                )));
            }
        }
        let Some(p) = is_texture("alpha") else {
            return Ok((microfacet(e, props)?, None));
        };
        if props.get("alpha_u").is_some() || props.get("alpha_v").is_some() {
            return Err(e.err("give alpha, or alpha_u and alpha_v, not both"));
        }
        let t = self.texture_or_ref(p)?;
        props.get("alpha"); // read here, not by microfacet
                            // Mitsuba's alpha texture is unbounded; ppm-vk's textures hold values in [0, 1] (Texture::check).
        if let Some(bad) = t.texture.out_of_range() {
            return Err(t.at.err(format!(
                "{}: {bad}: ppm-vk reads a roughness texture's values in [0, 1] only",
                t.texture.name
            )));
        }
        // Mitsuba's checkerboard evaluates eval_1 with its colours the other way round from eval (its
        // src/textures/checkerboard.cpp: color0 where u's and v's fractional parts are on different
        // sides of 1/2), each colour's eval_1 its channels' mean (src/spectra/srgb.cpp); the texture is
        // read as ppm-vk reads it (colour0 on the same side, then luminance), so it becomes that: the
        // colours swapped, each the grey of its mean (whose luminance is the mean).
        let t = match &t.texture.pattern {
            Pattern::Checkerboard { color0, color1 } => {
                let grey = |c: &Vec3| Vec3::splat((c.x + c.y + c.z) / 3.0);
                Rc::new(Tex {
                    texture: texture::Texture {
                        pattern: Pattern::Checkerboard {
                            color0: grey(color1),
                            color1: grey(color0),
                        },
                        ..t.texture.clone()
                    },
                    at: t.at.clone(),
                })
            }
            Pattern::Bitmap { .. } => t,
        };
        // Mitsuba's luminance (its src/core/spectrum.h) of the largest values: at least every point's.
        let alpha = t
            .texture
            .max()
            .dot(Vec3::new(0.212671, 0.715160, 0.072169))
            .max(Microfacet::MIN_ALPHA);
        let rough = microfacet_with(e, props, Some(alpha as f64))?;
        Ok((rough, Some(t)))
    }
}

/// A conductor's eta and k.
fn metal(e: &Elem, props: &Props) -> Result<(Vec3, Vec3)> {
    // Mitsuba's conductor: a named metal (its RGB eta and k, crates/materials/src/conductor.rs), or eta and
    // k given (both default to the "none" material's: a perfect mirror).
    let (none_eta, none_k) = conductors::named("none").expect("the default conductor");
    let (eta, k) = match props.string("material")? {
        Some(name) => {
            if props.get("eta").is_some() || props.get("k").is_some() {
                return Err(e.err("give a material name or eta and k, not both (Mitsuba refuses this too)"));
            }
            conductors::named(name).ok_or_else(|| {
                let known: Vec<&str> = conductors::names().collect();
                e.err(format!(
                    "unknown conductor material \"{name}\" (known: {})",
                    known.join(", ")
                ))
            })?
        }
        None => (
            props.color("eta")?.unwrap_or(none_eta),
            props.color("k")?.unwrap_or(none_k),
        ),
    };
    Ok((eta, k))
}

/// Mitsuba's `dielectric`: smooth glass, two-sided by nature.
fn dielectric(e: &Elem, props: &Props) -> Result<Bsdf> {
    let ior = glass_ior(e, props)?;
    Ok(Bsdf {
        surface: Surface::Glass { ior },
        two_sided: true,
        id: None,
        texture: None,
        normal_map: None,
        blend: None,
        opacity: None,
        specular: None,
        alpha: None,
    })
}

/// A dielectric's relative index of refraction int_ior / ext_ior (Mitsuba's defaults: bk7 in air);
/// ppm-vk glass is clear (specular reflectance and transmittance 1) and denser than its outside.
fn glass_ior(e: &Elem, props: &Props) -> Result<f32> {
    let (int, ext) = (ior(e, props, "int_ior", "bk7")?, ior(e, props, "ext_ior", "air")?);
    for name in ["specular_reflectance", "specular_transmittance"] {
        if let Some(c) = props.color(name)? {
            if c != Vec3::ONE {
                return Err(props
                    .get(name)
                    .unwrap()
                    .err("only 1 is supported (ppm-vk glass is clear and follows Fresnel)"));
            }
        }
    }
    if int < ext {
        return Err(e.err(format!(
            "int_ior {int} < ext_ior {ext}: ppm-vk glass is denser than its outside \
             (relative index >= 1)"
        )));
    }
    Ok((int / ext) as f32)
}

/// A rough BSDF's microfacet distribution: `distribution` (Mitsuba's default "beckmann", or "ggx") and
/// `alpha` (default 0.1), or `alpha_u` and `alpha_v` (anisotropic: along the shape's dp/du and across),
/// each raised to Mitsuba's floor 1e-4 as Mitsuba does; `sample_visible` changes only how Mitsuba samples
/// (ppm-vk always samples visible normals).
fn microfacet(e: &Elem, props: &Props) -> Result<Microfacet> {
    microfacet_with(e, props, None)
}

/// `microfacet`, its isotropic alpha `textured` when it is read from a texture.
fn microfacet_with(e: &Elem, props: &Props, textured: Option<f64>) -> Result<Microfacet> {
    let ggx = match props.string("distribution")? {
        None | Some("beckmann") => false,
        Some("ggx") => true,
        Some(other) => {
            let at = props.get("distribution").unwrap();
            return Err(at.err(format!("unknown distribution \"{other}\" (read: beckmann, ggx)")));
        }
    };
    props.ignore(&["sample_visible"]);
    let alpha = match textured {
        Some(a) => Some(a),
        None => props.float("alpha")?,
    };
    let (alpha_u, alpha_v) = match (alpha, props.float("alpha_u")?, props.float("alpha_v")?) {
        (Some(a), None, None) => (a, a),
        (None, None, None) => (0.1, 0.1),
        (None, Some(u), Some(v)) => (u, v),
        (Some(_), _, _) => return Err(e.err("give alpha, or alpha_u and alpha_v, not both")),
        (None, _, _) => return Err(e.err("give both alpha_u and alpha_v")),
    };
    for (name, a) in [("alpha", alpha_u), ("alpha_u", alpha_u), ("alpha_v", alpha_v)] {
        if let Some(at) = props
            .get(name)
            .filter(|_| textured.is_none() && !(a.is_finite() && a >= 0.0))
        {
            return Err(at.err(format!("must be finite and >= 0, got {a}")));
        }
    }
    let floor = |a: f64| (a as f32).max(Microfacet::MIN_ALPHA);
    Ok(Microfacet {
        ggx,
        alpha: floor(alpha_u),
        alpha_v: floor(alpha_v),
    })
}

/// A bsdf's index of refraction `name` (int_ior, ext_ior): a <float>, a <string> naming a material, or
/// Mitsuba's `default` when absent.
fn ior(e: &Elem, props: &Props, name: &str, default: &str) -> Result<f64> {
    let Some(p) = props.get(name) else {
        return ior_named(e, default);
    };
    match p.tag.as_str() {
        "float" => number(p, p.required("value")?),
        "string" => ior_named(p, p.required("value")?),
        _ => Err(p.err("expected a <float> or a <string> (a material name)")),
    }
}

fn ior_named(e: &Elem, name: &str) -> Result<f64> {
    if let Ok(v) = name.trim().parse::<f64>() {
        return Ok(v);
    }
    IOR_TABLE
        .iter()
        .find(|(n, _)| n.eq_ignore_ascii_case(name.trim()))
        .map(|(_, v)| *v)
        .ok_or_else(|| e.err(format!("unknown index of refraction \"{name}\"")))
}

#[cfg(test)]
mod tests {
    use super::super::tests::load_body;
    use super::*;
    use crate::Scene;

    fn surface_of(s: &Scene, sphere: usize) -> Surface {
        s.materials[s.spheres[sphere].material as usize].surface
    }

    #[test]
    fn materials_conductor_dielectric_and_emitter() {
        let s = load_body(
            r#"<shape type="sphere"><bsdf type="conductor"><rgb name="specular_reflectance" value="0.9, 0.8, 0.7"/></bsdf></shape>
               <shape type="sphere"><bsdf type="dielectric"><float name="int_ior" value="1.5"/><float name="ext_ior" value="1.25"/></bsdf></shape>
               <shape type="sphere"><bsdf type="dielectric"><string name="int_ior" value="water"/><string name="ext_ior" value="vacuum"/></bsdf></shape>
               <shape type="sphere"><bsdf type="dielectric"/></shape>"#,
        )
        .unwrap();
        let surface = |i: usize| s.materials[s.spheres[i].material as usize].surface;
        assert_eq!(
            surface(0),
            Surface::Mirror {
                reflectance: Vec3::new(0.9, 0.8, 0.7)
            }
        );
        assert_eq!(surface(1), Surface::Glass { ior: 1.2 });
        assert_eq!(surface(2), Surface::Glass { ior: 1.333 });
        // Mitsuba's defaults: bk7 in air.
        assert_eq!(
            surface(3),
            Surface::Glass {
                ior: (1.5046f64 / 1.000277) as f32
            }
        );
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
        // The light of HEAD: a black emitter with radiance 1, a quad facing -y.
        let lamp = &s.materials[s.quads[0].material as usize];
        assert_eq!(
            (lamp.surface, lamp.emission),
            (Surface::Diffuse { albedo: Vec3::ZERO }, Vec3::ONE)
        );
        assert!(s.quads[0].normal().distance(Vec3::NEG_Y) < 1e-6);

        // Rough conductors and dielectrics: Mitsuba's defaults (Beckmann, alpha 0.1), GGX, alpha_u and
        // alpha_v when equal, and Mitsuba's floor on alpha.
        let s = load_body(
            r#"<shape type="sphere"><bsdf type="roughconductor"/></shape>
               <shape type="sphere"><bsdf type="roughconductor"><string name="distribution" value="ggx"/>
                 <float name="alpha_u" value="0.3"/><float name="alpha_v" value="0.3"/><string name="material" value="Cu"/>
                 <boolean name="sample_visible" value="false"/></bsdf></shape>
               <shape type="sphere"><bsdf type="roughdielectric"><float name="alpha" value="0"/><float name="int_ior" value="1.5"/></bsdf></shape>"#,
        )
        .unwrap();
        let (none_eta, none_k) = conductors::named("none").unwrap();
        let (cu_eta, cu_k) = conductors::named("Cu").unwrap();
        assert_eq!(
            surface_of(&s, 0),
            Surface::RoughConductor {
                reflectance: Vec3::ONE,
                eta: none_eta,
                k: none_k,
                rough: Microfacet::isotropic(false, 0.1)
            }
        );
        assert_eq!(
            surface_of(&s, 1),
            Surface::RoughConductor {
                reflectance: Vec3::ONE,
                eta: cu_eta,
                k: cu_k,
                rough: Microfacet::isotropic(true, 0.3)
            }
        );
        assert_eq!(
            surface_of(&s, 2),
            Surface::RoughGlass {
                ior: (1.5 / 1.000277f64) as f32,
                rough: Microfacet::isotropic(false, Microfacet::MIN_ALPHA)
            }
        );
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
        // Anisotropic: alpha_u along the shape's dp/du, alpha_v across; refused where ppm-vk does not know
        // Mitsuba's dp/du (cube, disk, a rotated sphere) and on roughplastic (Mitsuba's is isotropic).
        let aniso = r#"<bsdf type="roughconductor"><float name="alpha_u" value="0.05"/><float name="alpha_v" value="0.3"/></bsdf>"#;
        let s = load_body(&format!(
            r#"<shape type="sphere">{aniso}</shape><shape type="rectangle">{aniso}</shape>"#
        ))
        .unwrap();
        assert_eq!(
            s.materials[s.spheres[0].material as usize].surface.rough(),
            Some(Microfacet {
                ggx: false,
                alpha: 0.05,
                alpha_v: 0.3
            })
        );
        for (shape, message) in [
            ("<shape type=\"cube\">", "anisotropic roughness on a cube"),
            ("<shape type=\"disk\">", "anisotropic roughness on a disk"),
            (
                "<shape type=\"sphere\"><transform name=\"to_world\"><rotate x=\"1\" angle=\"30\"/></transform>",
                "an anisotropic sphere whose to_world rotates",
            ),
        ] {
            let e = format!("{:#}", load_body(&format!("{shape}{aniso}</shape>")).unwrap_err());
            assert!(e.contains(message), "{shape}: {e}");
        }
        let e = format!(
            "{:#}",
            load_body(r#"<shape type="sphere"><bsdf type="roughplastic"><float name="alpha_u" value="0.05"/><float name="alpha_v" value="0.3"/></bsdf></shape>"#)
                .unwrap_err()
        );
        assert!(e.contains("roughplastic is isotropic"), "{e}");
        for (body, message) in [
            (
                r#"<string name="distribution" value="phong"/>"#,
                "unknown distribution \"phong\"",
            ),
            (
                r#"<float name="alpha" value="0.1"/><float name="alpha_u" value="0.1"/>"#,
                "not both",
            ),
            (
                r#"<float name="alpha_u" value="0.1"/>"#,
                "give both alpha_u and alpha_v",
            ),
            (r#"<float name="alpha" value="-1"/>"#, "must be finite and >= 0"),
        ] {
            for kind in ["roughconductor", "roughdielectric"] {
                let e = load_body(&format!(
                    r#"<shape type="sphere"><bsdf type="{kind}">{body}</bsdf></shape>"#
                ))
                .map(|_| ())
                .unwrap_err();
                let e = format!("{e:#}");
                assert!(e.contains(message) && e.contains("scene.xml:12:"), "{kind} {body}: {e}");
            }
        }
        // A named metal, and eta/k given as rgb or float: the conductor's Fresnel term.
        let s = load_body(
            r#"<shape type="sphere"><bsdf type="conductor"><string name="material" value="Au"/></bsdf></shape>
               <shape type="sphere"><bsdf type="conductor"><rgb name="eta" value="0.2, 0.9, 1.1"/><float name="k" value="3"/>
                 <rgb name="specular_reflectance" value="0.5"/></bsdf></shape>"#,
        )
        .unwrap();
        let (eta, k) = conductors::named("Au").unwrap();
        assert_eq!(
            surface_of(&s, 0),
            Surface::Conductor {
                reflectance: Vec3::ONE,
                eta,
                k
            }
        );
        assert_eq!(
            surface_of(&s, 1),
            Surface::Conductor {
                reflectance: Vec3::splat(0.5),
                eta: Vec3::new(0.2, 0.9, 1.1),
                k: Vec3::splat(3.0)
            }
        );
        for (body, said) in [
            (
                r#"<string name="material" value="Kryptonite"/>"#,
                "unknown conductor material \"Kryptonite\"",
            ),
            (
                r#"<string name="material" value="Au"/><float name="k" value="1"/>"#,
                "not both",
            ),
        ] {
            let e = load_body(&format!(
                r#"<shape type="sphere"><bsdf type="conductor">{body}</bsdf></shape>"#
            ));
            let e = format!("{:#}", e.unwrap_err());
            assert!(e.contains(said) && e.contains(r#"<bsdf type="conductor">"#), "{e}");
        }
        // Plastic and thin dielectric with Mitsuba's defaults (polypropylene and BK7 in air), and given;
        // rough plastic renders smooth with a warning, and a diffuse_reflectance above the photons' bound is
        // lowered with one.
        let s = load_body(
            r#"<shape type="sphere"><bsdf type="plastic"/></shape>
               <shape type="sphere"><bsdf type="plastic"><rgb name="diffuse_reflectance" value="0.1, 0.2, 0.3"/>
                 <float name="specular_reflectance" value="0.5"/><float name="int_ior" value="1.6"/>
                 <float name="ext_ior" value="1.25"/><boolean name="nonlinear" value="true"/></bsdf></shape>
               <shape type="sphere"><bsdf type="thindielectric"/></shape>
               <shape type="sphere"><bsdf type="thindielectric"><string name="int_ior" value="water"/>
                 <rgb name="specular_reflectance" value="0.5"/><rgb name="specular_transmittance" value="0.9, 0.8, 0.7"/></bsdf></shape>"#,
        )
        .unwrap();
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
        assert_eq!(
            surface_of(&s, 0),
            Surface::Plastic {
                diffuse: Vec3::splat(0.5),
                specular: Vec3::ONE,
                ior: (1.49f64 / 1.000277) as f32,
                nonlinear: false,
                rough: None
            }
        );
        assert_eq!(
            surface_of(&s, 1),
            Surface::Plastic {
                diffuse: Vec3::new(0.1, 0.2, 0.3),
                specular: Vec3::splat(0.5),
                ior: 1.28,
                nonlinear: true,
                rough: None
            }
        );
        assert_eq!(
            surface_of(&s, 2),
            Surface::ThinDielectric {
                ior: (1.5046f64 / 1.000277) as f32,
                reflectance: Vec3::ONE,
                transmittance: Vec3::ONE
            }
        );
        assert_eq!(
            surface_of(&s, 3),
            Surface::ThinDielectric {
                ior: (1.333f64 / 1.000277) as f32,
                reflectance: Vec3::splat(0.5),
                transmittance: Vec3::new(0.9, 0.8, 0.7)
            }
        );
        let s = load_body(
            r#"<shape type="sphere"><bsdf type="roughplastic"><float name="alpha" value="0.2"/>
                 <rgb name="diffuse_reflectance" value="0.99, 0.5, 0.2"/></bsdf></shape>"#,
        )
        .unwrap();
        // roughplastic: Mitsuba's default Beckmann, the bound of its rough coat (which transmits less than
        // a smooth one at normal incidence, so it may allow 0.99).
        let ior = (1.49f64 / 1.000277) as f32;
        let rough = Some(Microfacet::isotropic(false, 0.2));
        let most = crate::plastic::max_diffuse_reflectance(ior, false, &crate::plastic::coat(ior, rough));
        let lowered = most < 0.99;
        assert!(
            s.warnings.len() == lowered as usize
                && s.warnings
                    .iter()
                    .all(|w| w.contains("diffuse_reflectance [0.99, 0.5, 0.2] lowered")),
            "{most}: {:?}",
            s.warnings
        );
        assert!(matches!(surface_of(&s, 0),
            Surface::Plastic { diffuse, rough: r, .. } if diffuse == Vec3::new(most.min(0.99), 0.5, 0.2) && r == rough));
        // One-sided diffuse on an open shape: warned; on a closed one or twosided: not.
        let s = load_body(r#"<shape type="rectangle"><bsdf type="diffuse"/></shape><shape type="cube"><bsdf type="diffuse"/></shape>"#).unwrap();
        assert!(
            s.warnings.len() == 1 && s.warnings[0].contains("one-sided in Mitsuba"),
            "{:?}",
            s.warnings
        );
        // A shape without a bsdf is diffuse 0.5, as in Mitsuba.
        let s = load_body(r#"<shape type="cube"/>"#).unwrap();
        assert_eq!(
            s.materials[s.quads[1].material as usize].surface,
            Surface::Diffuse {
                albedo: Vec3::splat(0.5)
            }
        );
    }
}

#[cfg(test)]
mod texture_tests {
    use super::super::tests::{load_in, write_texture};
    use super::*;
    use crate::{Scene, TempDir};

    const TEX: &str = r#"<texture type="bitmap" name="NAME"><string name="filename" value="t.png"/></texture>"#;

    fn load(body: &str) -> Result<Scene> {
        let dir = TempDir::new("mitsuba-param-textures");
        write_texture(&dir, "t.png");
        load_in(&dir, body, &[])
    }

    /// specular_reflectance on conductor, roughconductor and thindielectric, alpha on roughconductor and
    /// roughdielectric (nested or a ref): the materials' specular_texture and alpha_texture, the surface's
    /// constants the texture's largest values (alpha: their luminance), the texture interned once.
    #[test]
    fn specular_and_alpha_textures_are_read() {
        let spec = TEX.replace("NAME", "specular_reflectance");
        let alpha = TEX.replace("NAME", "alpha");
        let s = load(&format!(
            r#"<texture type="bitmap" id="shared"><string name="filename" value="t.png"/></texture>
               <shape type="sphere"><bsdf type="conductor">{spec}</bsdf></shape>
               <shape type="sphere"><bsdf type="roughconductor"><ref name="specular_reflectance" id="shared"/>{alpha}<string name="material" value="Au"/></bsdf></shape>
               <shape type="sphere"><bsdf type="thindielectric">{spec}</bsdf></shape>
               <shape type="sphere"><bsdf type="roughdielectric"><string name="distribution" value="ggx"/>{alpha}</bsdf></shape>"#
        ))
        .unwrap();
        let m = |i: usize| &s.materials[s.spheres[i].material as usize];
        assert_eq!(s.textures.len(), 1, "one image, interned once");
        assert_eq!(m(0).surface, Surface::Mirror { reflectance: Vec3::ONE });
        assert_eq!((m(0).specular_texture, m(0).alpha_texture), (Some(0), None));
        assert_eq!((m(1).specular_texture, m(1).alpha_texture), (Some(0), Some(0)));
        // The image's largest values are 1 in each channel: luminance 1.
        assert!(
            matches!(m(1).surface, Surface::RoughConductor { reflectance, rough, .. }
            if reflectance == Vec3::ONE && (rough.alpha - 1.0).abs() < 1e-6 && !rough.is_anisotropic())
        );
        assert_eq!((m(2).specular_texture, m(2).alpha_texture), (Some(0), None));
        assert_eq!((m(3).specular_texture, m(3).alpha_texture), (None, Some(0)));
        assert!(matches!(m(3).surface, Surface::RoughGlass { rough, .. } if rough.ggx));
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);

        // A checkerboard's alpha: Mitsuba's eval_1 swaps its colours and takes each one's mean.
        let s = load(
            r#"<shape type="sphere"><bsdf type="roughconductor"><texture type="checkerboard" name="alpha">
                 <rgb name="color0" value="0.1, 0.2, 0.3"/><float name="color1" value="0.05"/></texture></bsdf></shape>"#,
        )
        .unwrap();
        let m = &s.materials[s.spheres[0].material as usize];
        let t = &s.textures[m.alpha_texture.unwrap() as usize];
        assert!(
            matches!(t.pattern, crate::texture::Pattern::Checkerboard { color0, color1 }
                if color0 == Vec3::splat(0.05) && (color1 - Vec3::splat(0.2)).abs().max_element() < 1e-7),
            "{t:?}"
        );
        // Refused, by name: what ppm-vk does not read yet, and what Mitsuba refuses.
        let alpha_u = TEX.replace("NAME", "alpha_u");
        for (body, said) in [
            (
                format!(r#"<bsdf type="plastic">{spec}</bsdf>"#),
                "a texture on plastic's specular_reflectance is not supported yet",
            ),
            (
                format!(r#"<bsdf type="roughplastic">{alpha}</bsdf>"#),
                "a texture on roughplastic's alpha is not supported (Mitsuba 3 reads it as a float",
            ),
            (
                format!(r#"<bsdf type="roughconductor">{alpha_u}<float name="alpha_v" value="0.2"/></bsdf>"#),
                "a texture on alpha_u is not supported yet",
            ),
            (
                format!(r#"<bsdf type="roughconductor">{alpha}<float name="alpha_u" value="0.2"/></bsdf>"#),
                "give alpha, or alpha_u and alpha_v, not both",
            ),
            (
                TEX.replace("NAME", "specular_transmittance")
                    .replace("<texture", r#"<bsdf type="thindielectric"><texture"#)
                    + "</bsdf>",
                "a texture on a thindielectric's specular_transmittance is not supported yet",
            ),
        ] {
            let e = format!(
                "{:#}",
                load(&format!(r#"<shape type="sphere">{body}</shape>"#)).unwrap_err()
            );
            assert!(e.contains(said) && e.contains("scene.xml:"), "{body}: {e}");
        }
    }
}
