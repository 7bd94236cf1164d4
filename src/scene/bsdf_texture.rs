//! A Mitsuba BSDF's parameters given by textures (`<texture name="alpha_u" …>` inside a
//! `roughconductor`, say): which parameter, read from which texture, and the BSDF they make
//! at a hit.

use super::bsdf::{Bsdf, Microfacet};
use super::{Scene, SurfaceHit};

/// A number of a BSDF that a texture may give.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BsdfParameter {
    /// A microfacet distribution's roughness along the frame's first tangent (`alpha_u`).
    AlphaU,
    /// … along its second tangent (`alpha_v`).
    AlphaV,
    /// … along both (`alpha`).
    Alpha,
    Roughness,
    Anisotropic,
    Metallic,
    Specular,
    SpecTint,
    SpecTrans,
    Sheen,
    SheenTint,
    Clearcoat,
    ClearcoatGloss,
    Flatness,
    /// `principledthin`'s relative index (`eta`).
    Eta,
    /// `principledthin`'s diffuse transmission (`diff_trans`).
    DiffTrans,
}

impl BsdfParameter {
    /// The parameter of Mitsuba's name, for the BSDFs that have it.
    pub fn named(name: &str) -> Option<BsdfParameter> {
        Some(match name {
            "alpha_u" => BsdfParameter::AlphaU,
            "alpha_v" => BsdfParameter::AlphaV,
            "alpha" => BsdfParameter::Alpha,
            "roughness" => BsdfParameter::Roughness,
            "anisotropic" => BsdfParameter::Anisotropic,
            "metallic" => BsdfParameter::Metallic,
            "specular" => BsdfParameter::Specular,
            "spec_tint" => BsdfParameter::SpecTint,
            "spec_trans" => BsdfParameter::SpecTrans,
            "sheen" => BsdfParameter::Sheen,
            "sheen_tint" => BsdfParameter::SheenTint,
            "clearcoat" => BsdfParameter::Clearcoat,
            "clearcoat_gloss" => BsdfParameter::ClearcoatGloss,
            "flatness" => BsdfParameter::Flatness,
            "eta" => BsdfParameter::Eta,
            "diff_trans" => BsdfParameter::DiffTrans,
            _ => return None,
        })
    }

    /// `bsdf` with this parameter set to `value` (a BSDF without it is left as it is).
    fn set(self, bsdf: &mut Bsdf, value: f32) {
        use BsdfParameter::*;
        let rough = |d: &mut Option<Microfacet>| {
            if let Some(m) = d {
                let (u, v) = m.alpha();
                let (u, v) = match self {
                    AlphaU => (value, v),
                    AlphaV => (u, value),
                    _ => (value, value),
                };
                *m = Microfacet::new(m.kind(), u, v, m.sample_visible());
            }
        };
        match bsdf {
            Bsdf::Conductor { distribution, .. } | Bsdf::Dielectric { distribution, .. }
                if matches!(self, AlphaU | AlphaV | Alpha) =>
            {
                rough(distribution)
            }
            Bsdf::Principled(p) => {
                let field = match self {
                    Roughness => &mut p.roughness,
                    Anisotropic => &mut p.anisotropic,
                    Metallic => &mut p.metallic,
                    Specular => &mut p.specular,
                    SpecTint => &mut p.spec_tint,
                    SpecTrans => &mut p.spec_trans,
                    Sheen => &mut p.sheen,
                    SheenTint => &mut p.sheen_tint,
                    Clearcoat => &mut p.clearcoat,
                    ClearcoatGloss => &mut p.clearcoat_gloss,
                    Flatness => &mut p.flatness,
                    AlphaU | AlphaV | Alpha | Eta | DiffTrans => return,
                };
                *field = value;
            }
            Bsdf::PrincipledThin(p) => {
                let field = match self {
                    Roughness => &mut p.roughness,
                    Anisotropic => &mut p.anisotropic,
                    SpecTint => &mut p.spec_tint,
                    SpecTrans => &mut p.spec_trans,
                    Sheen => &mut p.sheen,
                    SheenTint => &mut p.sheen_tint,
                    Flatness => &mut p.flatness,
                    Eta => &mut p.eta,
                    DiffTrans => &mut p.diff_trans,
                    AlphaU | AlphaV | Alpha | Metallic | Specular | Clearcoat | ClearcoatGloss => {
                        return
                    }
                };
                *field = value;
            }
            _ => {}
        }
    }
}

/// A parameter of a material's BSDF read from one of `Scene::textures` (its first channel).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TexturedParameter {
    pub parameter: BsdfParameter,
    pub texture: usize,
}

impl Scene {
    /// The material's BSDF at `hit` with its textured parameters read there, and a textured
    /// diffuse reflectance or principled base colour; None where nothing of it is textured.
    pub fn textured_bsdf(&self, hit: &SurfaceHit, bsdf: &Bsdf) -> Option<Bsdf> {
        let m = &self.materials[hit.material as usize];
        let base_textured = matches!(
            bsdf,
            Bsdf::Principled(_) | Bsdf::PrincipledThin(_) | Bsdf::Diffuse { .. }
        ) && m.texture.is_some();
        if m.bsdf_textures.is_empty() && !base_textured {
            return None;
        }
        let st = self.tex_coords(hit);
        let mut textured = bsdf.clone();
        for p in &m.bsdf_textures {
            p.parameter
                .set(&mut textured, self.textures[p.texture].lookup(st).x);
        }
        if base_textured {
            match &mut textured {
                Bsdf::Principled(p) => p.base_color = self.albedo(hit),
                Bsdf::PrincipledThin(p) => p.base_color = self.albedo(hit),
                Bsdf::Diffuse { reflectance } => *reflectance = self.albedo(hit),
                _ => {}
            }
        }
        Some(textured)
    }
}
