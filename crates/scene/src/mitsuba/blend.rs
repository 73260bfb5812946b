//! Mitsuba's `blendbsdf` (src/bsdfs/blendbsdf.cpp): two nested bsdfs and a `weight` (a float or a texture,
//! default 0.5), f = (1 - w) f_0 + w f_1. Each component becomes a scene material of its own and the
//! blend a `Surface::Blend` of the two (bsdf.rs's `material`).

use std::rc::Rc;

use anyhow::Result;

use super::bsdf::{Bsdf, Perturbation};
use super::elem::Elem;
use super::properties::Props;
use super::texture::Tex;
use super::Builder;
use crate::{Surface, MAX_BLEND_DEPTH};

/// A blend as read: its weight (a constant, or the luminance of `texture`) and its two components.
#[derive(Debug)]
pub(super) struct Blend {
    pub(super) weight: f32,
    pub(super) texture: Option<Rc<Tex>>,
    pub(super) first: Bsdf,
    pub(super) second: Bsdf,
}

impl Bsdf {
    /// The plain bsdfs it is made of: itself, or a blend's components' (in order).
    pub(super) fn leaves(&self) -> Vec<&Bsdf> {
        match &self.blend {
            Some(b) => [b.first.leaves(), b.second.leaves()].concat(),
            None => vec![self],
        }
    }

    /// How many blends deep it is (0: not a blend).
    pub(super) fn blend_depth(&self) -> u32 {
        self.blend
            .as_ref()
            .map_or(0, |b| 1 + b.first.blend_depth().max(b.second.blend_depth()))
    }

    /// Whether anything in it reads texture coordinates: a texture, a bump or normal map, a blend's weight.
    pub(super) fn textured(&self) -> bool {
        match &self.blend {
            Some(b) => b.texture.is_some() || b.first.textured() || b.second.textured(),
            None => self.texture.is_some() || self.normal_map.is_some(),
        }
    }

    /// `self` with bump or normal map `p`: a blend's components each get it. A bump map around a blend
    /// is the blend of the components bumped alike, exactly: both read the same perturbed frame, and the
    /// shadowing term multiplies each. Fails where a component has a map of its own.
    pub(super) fn perturbed(self, p: &Perturbation) -> Option<Bsdf> {
        if self.normal_map.is_some() {
            return None;
        }
        let Some(b) = self.blend else {
            return Some(Bsdf {
                normal_map: Some(p.clone()),
                ..self
            });
        };
        let Blend {
            weight,
            texture,
            first,
            second,
        } = Rc::try_unwrap(b).unwrap_or_else(|b| Blend {
            weight: b.weight,
            texture: b.texture.clone(),
            first: b.first.clone(),
            second: b.second.clone(),
        });
        Some(Bsdf {
            blend: Some(Rc::new(Blend {
                weight,
                texture,
                first: first.perturbed(p)?,
                second: second.perturbed(p)?,
            })),
            ..self
        })
    }
}

impl Builder {
    /// Mitsuba's `blendbsdf`: two nested bsdfs (elements or `ref`s, in the order written) and `weight`.
    pub(super) fn blendbsdf(&mut self, e: &Elem, props: &Props, objects: &[&Elem]) -> Result<Bsdf> {
        let mut parts = Vec::new();
        for &o in objects {
            parts.push(match o.tag.as_str() {
                "bsdf" => (self.bsdf(o)?, o),
                "ref" => (self.bsdf_ref(o)?, o),
                _ => return Err(o.err(format!("not expected inside {}", e.what()))),
            });
        }
        let (first, second) = match <[(Bsdf, &Elem); 2]>::try_from(parts) {
            Ok([(a, _), (b, _)]) => (a, b),
            Err(parts) => {
                return Err(match parts.get(2) {
                    Some((_, third)) => third.err("a third bsdf: a blendbsdf blends two (as in Mitsuba)"),
                    None => e.err(format!(
                        "needs two nested bsdfs (as in Mitsuba), has {}",
                        parts.len()
                    )),
                })
            }
        };
        let (weight, texture) = match props.get("weight") {
            Some(t) if t.tag == "texture" || t.tag == "ref" => {
                let t = match t.tag.as_str() {
                    "texture" => Rc::new(self.texture(t)?),
                    _ => {
                        let id = t.required("id")?;
                        self.textures
                            .get(id)
                            .cloned()
                            .ok_or_else(|| t.err(format!("no texture with id \"{id}\" defined before it")))?
                    }
                };
                if let Some(bad) = t.texture.out_of_range() {
                    return Err(t.at.err(format!(
                        "{}: {bad}: a blend weight texture's values must be in [0, 1] (Mitsuba would clip \
                         them)",
                        t.texture.name
                    )));
                }
                // Unread: the texture gives the weight.
                (0.5, Some(t))
            }
            _ => {
                let w = props.float("weight")?.unwrap_or(0.5);
                if !(0.0..=1.0).contains(&w) {
                    return Err(props.get("weight").unwrap().err(format!(
                        "must be in [0, 1], got {w} (Mitsuba would clip it)"
                    )));
                }
                (w as f32, None)
            }
        };
        let blend = Blend {
            weight,
            texture,
            first,
            second,
        };
        let depth = 1 + blend.first.blend_depth().max(blend.second.blend_depth());
        if depth > MAX_BLEND_DEPTH {
            return Err(e.err(format!(
                "blendbsdfs nested {depth} deep, more than MAX_BLEND_DEPTH = {MAX_BLEND_DEPTH}"
            )));
        }
        let two_sided = blend.first.two_sided && blend.second.two_sided;
        Ok(Bsdf {
            // The components' materials are made with the blend's (bsdf.rs's `material`).
            surface: Surface::Blend {
                weight,
                first: 0,
                second: 0,
            },
            two_sided,
            id: None,
            texture: None,
            normal_map: None,
            blend: Some(Rc::new(blend)),
        })
    }
}
