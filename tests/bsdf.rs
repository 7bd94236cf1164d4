//! The Mitsuba 3 BSDFs of `scene::bsdf` against four checks that each fail on a wrong
//! model: a white furnace (no BSDF returns more energy than it receives, and the lossless
//! ones return all of it), a χ² test of `sample`'s directions against `pdf` (the density
//! the path tracer's multiple importance sampling divides by), `sample`'s weight against
//! `eval / pdf`, and values of `eval`, `pdf` and `sample` against Mitsuba 3's own.

use trilux::geometry::{vec3, Vec3};
use trilux::sampling::Rng;
use trilux::scene::bsdf::{
    fresnel_dielectric, Bsdf, BsdfSample, Microfacet, MicrofacetKind, Plastic, Principled,
    PrincipledThin,
};

use MicrofacetKind::{Beckmann, Ggx};

fn mf(kind: MicrofacetKind, au: f32, av: f32, visible: bool) -> Option<Microfacet> {
    Some(Microfacet::new(kind, au, av, visible))
}

/// The BSDFs the Mitsuba values were computed for, by the names the tables use (each the
/// Mitsuba plugin and parameters written in `mitsuba_dict`).
fn named(name: &str) -> Bsdf {
    let metal = (vec3(0.2, 0.9, 1.1), vec3(3.9, 2.4, 2.2));
    match name {
        // {'type': 'roughconductor', 'distribution': 'ggx', 'alpha': 0.3, eta, k}
        "conductor_ggx" => Bsdf::Conductor {
            eta: metal.0,
            k: metal.1,
            specular: Vec3::ONE,
            distribution: mf(Ggx, 0.3, 0.3, true),
        },
        // {'type': 'roughconductor', 'distribution': 'beckmann', 'alpha_u': 0.2,
        //  'alpha_v': 0.4, 'sample_visible': False, 'specular_reflectance': [.9, .8, .7]}
        "conductor_beckmann_aniso_plain" => Bsdf::Conductor {
            eta: vec3(1.5, 1.2, 0.9),
            k: vec3(2.0, 2.5, 3.0),
            specular: vec3(0.9, 0.8, 0.7),
            distribution: mf(Beckmann, 0.2, 0.4, false),
        },
        // {'type': 'roughconductor', 'distribution': 'beckmann', 'alpha': 0.25, eta, k}
        "conductor_beckmann" => Bsdf::Conductor {
            eta: metal.0,
            k: metal.1,
            specular: Vec3::ONE,
            distribution: mf(Beckmann, 0.25, 0.25, true),
        },
        // {'type': 'roughdielectric', 'distribution': 'ggx', 'alpha_u': 0.2,
        //  'alpha_v': 0.35, 'sample_visible': False, 'int_ior': 1.7, 'ext_ior': 1.1}
        "dielectric_ggx_aniso_plain" => Bsdf::Dielectric {
            eta: 1.7 / 1.1,
            reflectance: Vec3::ONE,
            transmittance: Vec3::ONE,
            distribution: mf(Ggx, 0.2, 0.35, false),
        },
        // {'type': 'roughconductor', 'distribution': 'ggx', 'alpha_u': 0.15,
        //  'alpha_v': 0.35, eta, k}
        "conductor_ggx_aniso" => Bsdf::Conductor {
            eta: metal.0,
            k: metal.1,
            specular: Vec3::ONE,
            distribution: mf(Ggx, 0.15, 0.35, true),
        },
        // {'type': 'conductor', eta, k}
        "conductor_smooth" => Bsdf::Conductor {
            eta: metal.0,
            k: metal.1,
            specular: Vec3::ONE,
            distribution: None,
        },
        // {'type': 'roughdielectric', 'distribution': 'ggx', 'alpha': 0.25,
        //  'int_ior': 1.5, 'ext_ior': 1.0}
        "dielectric_ggx" => Bsdf::Dielectric {
            eta: 1.5,
            reflectance: Vec3::ONE,
            transmittance: Vec3::ONE,
            distribution: mf(Ggx, 0.25, 0.25, true),
        },
        // {'type': 'roughdielectric', 'distribution': 'beckmann', 'alpha': 0.3,
        //  'sample_visible': False, 'int_ior': 1.33, 'specular_reflectance': [.9, .9, .8],
        //  'specular_transmittance': [.7, .8, .9]}
        "dielectric_beckmann_plain" => Bsdf::Dielectric {
            eta: 1.33,
            reflectance: vec3(0.9, 0.9, 0.8),
            transmittance: vec3(0.7, 0.8, 0.9),
            distribution: mf(Beckmann, 0.3, 0.3, false),
        },
        "dielectric_smooth" => Bsdf::Dielectric {
            eta: 1.5,
            reflectance: Vec3::ONE,
            transmittance: Vec3::ONE,
            distribution: None,
        },
        "thin" => Bsdf::ThinDielectric {
            eta: 1.5,
            reflectance: Vec3::ONE,
            transmittance: Vec3::ONE,
        },
        // {'type': 'roughplastic', 'distribution': 'ggx', 'alpha': 0.2,
        //  'diffuse_reflectance': [.6, .3, .1], 'int_ior': 1.49, 'ext_ior': 1.0}
        "plastic_rough_ggx" => Bsdf::Plastic(Plastic::new(
            vec3(0.6, 0.3, 0.1),
            Vec3::ONE,
            1.49,
            false,
            mf(Ggx, 0.2, 0.2, true),
        )),
        // {'type': 'roughplastic', 'distribution': 'beckmann', 'alpha': 0.3,
        //  'nonlinear': True, 'diffuse_reflectance': [.8, .5, .2],
        //  'specular_reflectance': .8, 'int_ior': 1.6, 'ext_ior': 1.0}
        "plastic_rough_beckmann_nonlinear" => Bsdf::Plastic(Plastic::new(
            vec3(0.8, 0.5, 0.2),
            Vec3::splat(0.8),
            1.6,
            true,
            mf(Beckmann, 0.3, 0.3, true),
        )),
        // {'type': 'plastic', 'diffuse_reflectance': [.2, .5, .7], 'int_ior': 1.49}
        "plastic_smooth" => Bsdf::Plastic(Plastic::new(
            vec3(0.2, 0.5, 0.7),
            Vec3::ONE,
            1.49,
            false,
            None,
        )),
        // {'type': 'plastic', 'diffuse_reflectance': [.9, .5, .2], 'nonlinear': True,
        //  'int_ior': 1.7}
        "plastic_smooth_nonlinear" => Bsdf::Plastic(Plastic::new(
            vec3(0.9, 0.5, 0.2),
            Vec3::ONE,
            1.7,
            true,
            None,
        )),
        // {'type': 'diffuse', 'reflectance': [.3, .6, .9]}
        "diffuse" => Bsdf::Diffuse {
            reflectance: vec3(0.3, 0.6, 0.9),
        },
        // {'type': 'principled', 'base_color': [.8, .4, .2], 'roughness': 0.4,
        //  'metallic': 0.3, 'spec_tint': 0.5, 'sheen': 0.6, 'sheen_tint': 0.4,
        //  'clearcoat': 0.7, 'clearcoat_gloss': 0.5, 'flatness': 0.3,
        //  'anisotropic': 0.5, 'specular': 0.6}
        "principled_opaque" => Bsdf::Principled(Principled {
            base_color: vec3(0.8, 0.4, 0.2),
            roughness: 0.4,
            metallic: 0.3,
            spec_tint: 0.5,
            sheen: 0.6,
            sheen_tint: 0.4,
            clearcoat: 0.7,
            clearcoat_gloss: 0.5,
            flatness: 0.3,
            anisotropic: 0.5,
            specular: 0.6,
            ..Principled::default()
        }),
        // {'type': 'principled', 'base_color': [.9, .7, .5], 'roughness': 0.3,
        //  'spec_trans': 0.6, 'eta': 1.45, 'metallic': 0.1}
        "principled_glass" => Bsdf::Principled(Principled {
            base_color: vec3(0.9, 0.7, 0.5),
            roughness: 0.3,
            spec_trans: 0.6,
            eta: Some(1.45),
            metallic: 0.1,
            ..Principled::default()
        }),
        // {'type': 'principledthin', 'base_color': [.8, .5, .3], 'roughness': 0.4,
        //  'anisotropic': 0.5, 'spec_trans': 0.6, 'eta': 1.4, 'spec_tint': 0.4,
        //  'sheen': 0.5, 'sheen_tint': 0.3, 'flatness': 0.4, 'diff_trans': 0.8}
        "thin_glossy" => Bsdf::PrincipledThin(PrincipledThin {
            base_color: vec3(0.8, 0.5, 0.3),
            roughness: 0.4,
            anisotropic: 0.5,
            spec_trans: 0.6,
            eta: 1.4,
            spec_tint: 0.4,
            sheen: 0.5,
            sheen_tint: 0.3,
            flatness: 0.4,
            diff_trans: 0.8,
            ..PrincipledThin::default()
        }),
        // {'type': 'principledthin', 'base_color': [.3, .6, .9], 'roughness': 0.7,
        //  'diff_trans': 1.3, 'sheen': 0.3, 'diffuse_transmittance_sampling_rate': 2.0}
        "thin_diffuse" => Bsdf::PrincipledThin(PrincipledThin {
            base_color: vec3(0.3, 0.6, 0.9),
            roughness: 0.7,
            diff_trans: 1.3,
            sheen: 0.3,
            diffuse_transmittance_sampling_rate: 2.0,
            ..PrincipledThin::default()
        }),
        _ => panic!("no BSDF named {name}"),
    }
}

struct EvalCase {
    bsdf: &'static str,
    wi: [f32; 3],
    wo: [f32; 3],
    eval: [f32; 3],
    pdf: f32,
}

struct SampleCase {
    bsdf: &'static str,
    wi: [f32; 3],
    u: f32,
    u2: (f32, f32),
    wo: [f32; 3],
    pdf: f32,
    weight: [f32; 3],
}

// Mitsuba 3.9.1's values (scalar_rgb variant, `mi.load_dict` of the dictionaries written
// in `named`, then `bsdf.eval`, `bsdf.pdf` and `bsdf.sample` with a default
// `BSDFContext` and `SurfaceInteraction3f` whose `wi` is given), for these inputs.
#[rustfmt::skip]
const EVAL_CASES: &[EvalCase] = &[
    EvalCase { bsdf: "conductor_ggx", wi: [0.3487429, 0.11624764, 0.9299811], wo: [-0.48154342, 0.24077171, 0.84270096], eval: [0.42722633, 0.2763774, 0.2354387], pdf: 0.4529564 },
    EvalCase { bsdf: "conductor_ggx", wi: [0.7442084, -0.24806947, 0.6201737], wo: [-0.63500065, 0.12700012, 0.76200074], eval: [0.99331796, 0.6443386, 0.5520524], pdf: 1.0624545 },
    EvalCase { bsdf: "conductor_ggx", wi: [0.049927656, 0.019971063, 0.99855316], wo: [0.38411063, 0.51214755, 0.76822126], eval: [0.1532962, 0.09916459, 0.084447086], pdf: 0.16352062 },
    EvalCase { bsdf: "conductor_ggx", wi: [0.97618705, 0.0, 0.21693046], wo: [-0.94345635, 0.104828484, 0.31448546], eval: [1.2201934, 0.87762594, 0.79447335], pdf: 1.5210553 },
    EvalCase { bsdf: "conductor_beckmann_aniso_plain", wi: [0.3487429, 0.11624764, 0.9299811], wo: [-0.48154342, 0.24077171, 0.84270096], eval: [0.2949412, 0.35819754, 0.3946864], pdf: 0.79189813 },
    EvalCase { bsdf: "conductor_beckmann_aniso_plain", wi: [0.7442084, -0.24806947, 0.6201737], wo: [-0.63500065, 0.12700012, 0.76200074], eval: [0.50912017, 0.6097551, 0.6683806], pdf: 1.1900418 },
    EvalCase { bsdf: "conductor_beckmann_aniso_plain", wi: [0.049927656, 0.019971063, 0.99855316], wo: [0.38411063, 0.51214755, 0.76822126], eval: [0.061812524, 0.07513152, 0.08280765], pdf: 0.16261603 },
    EvalCase { bsdf: "conductor_beckmann_aniso_plain", wi: [0.97618705, 0.0, 0.21693046], wo: [-0.94345635, 0.104828484, 0.31448546], eval: [1.6490494, 1.7460645, 1.7798973], pdf: 2.7838652 },
    EvalCase { bsdf: "conductor_beckmann", wi: [0.3487429, 0.11624764, 0.9299811], wo: [-0.48154342, 0.24077171, 0.84270096], eval: [0.6812825, 0.44072914, 0.37544563], pdf: 0.71579885 },
    EvalCase { bsdf: "conductor_beckmann", wi: [0.7442084, -0.24806947, 0.6201737], wo: [-0.63500065, 0.12700012, 0.76200074], eval: [1.6046302, 1.0408804, 0.8917989], pdf: 1.6892961 },
    EvalCase { bsdf: "conductor_beckmann", wi: [0.049927656, 0.019971063, 0.99855316], wo: [0.38411063, 0.51214755, 0.76822126], eval: [0.14342989, 0.092782244, 0.07901198], pdf: 0.1506776 },
    EvalCase { bsdf: "conductor_beckmann", wi: [0.97618705, 0.0, 0.21693046], wo: [-0.94345635, 0.104828484, 0.31448546], eval: [2.9105487, 2.0934165, 1.8950711], pdf: 3.0988483 },
    EvalCase { bsdf: "dielectric_ggx_aniso_plain", wi: [0.3487429, 0.11624764, 0.9299811], wo: [-0.48154342, 0.24077171, 0.84270096], eval: [0.028604025, 0.028604025, 0.028604025], pdf: 0.02875806 },
    EvalCase { bsdf: "dielectric_ggx_aniso_plain", wi: [0.7442084, -0.24806947, 0.6201737], wo: [-0.63500065, 0.12700012, 0.76200074], eval: [0.0713809, 0.0713809, 0.0713809], pdf: 0.061439198 },
    EvalCase { bsdf: "dielectric_ggx_aniso_plain", wi: [0.049927656, 0.019971063, 0.99855316], wo: [0.38411063, 0.51214755, 0.76822126], eval: [0.0064870757, 0.0064870757, 0.0064870757], pdf: 0.006472445 },
    EvalCase { bsdf: "dielectric_ggx_aniso_plain", wi: [0.3487429, 0.11624764, 0.9299811], wo: [-0.21566555, -0.107832775, -0.970495], eval: [11.086526, 11.086526, 11.086526], pdf: 26.210493 },
    EvalCase { bsdf: "dielectric_ggx_aniso_plain", wi: [0.22792116, 0.34188172, -0.91168463], wo: [-0.51214755, -0.38411063, 0.76822126], eval: [2.0616522, 2.0616522, 2.0616522], pdf: 0.86386883 },
    EvalCase { bsdf: "dielectric_ggx_aniso_plain", wi: [0.22792116, 0.34188172, -0.91168463], wo: [-0.38100037, -0.25400025, -0.8890009], eval: [0.04622159, 0.04622159, 0.04622159], pdf: 0.046227366 },
    EvalCase { bsdf: "dielectric_ggx_aniso_plain", wi: [0.97618705, 0.0, 0.21693046], wo: [-0.94345635, 0.104828484, 0.31448546], eval: [0.5522599, 0.5522599, 0.5522599], pdf: 0.5019256 },
    EvalCase { bsdf: "conductor_ggx_aniso", wi: [0.3487429, 0.11624764, 0.9299811], wo: [-0.48154342, 0.24077171, 0.84270096], eval: [0.67586637, 0.4372254, 0.3724609], pdf: 0.7131747 },
    EvalCase { bsdf: "conductor_ggx_aniso", wi: [0.7442084, -0.24806947, 0.6201737], wo: [-0.63500065, 0.12700012, 0.76200074], eval: [1.3059614, 0.847142, 0.725809], pdf: 1.3813779 },
    EvalCase { bsdf: "conductor_ggx_aniso", wi: [0.049927656, 0.019971063, 0.99855316], wo: [0.38411063, 0.51214755, 0.76822126], eval: [0.09644055, 0.062385682, 0.05312672], pdf: 0.102813125 },
    EvalCase { bsdf: "conductor_ggx_aniso", wi: [0.97618705, 0.0, 0.21693046], wo: [-0.94345635, 0.104828484, 0.31448546], eval: [2.7935946, 2.0092971, 1.8189218], pdf: 3.1172788 },
    EvalCase { bsdf: "dielectric_ggx", wi: [0.3487429, 0.11624764, 0.9299811], wo: [-0.48154342, 0.24077171, 0.84270096], eval: [0.019987253, 0.019987253, 0.019987253], pdf: 0.02011392 },
    EvalCase { bsdf: "dielectric_ggx", wi: [0.7442084, -0.24806947, 0.6201737], wo: [-0.63500065, 0.12700012, 0.76200074], eval: [0.069956824, 0.069956824, 0.069956824], pdf: 0.07073755 },
    EvalCase { bsdf: "dielectric_ggx", wi: [0.049927656, 0.019971063, 0.99855316], wo: [0.38411063, 0.51214755, 0.76822126], eval: [0.005754133, 0.005754133, 0.005754133], pdf: 0.0058159065 },
    EvalCase { bsdf: "dielectric_ggx", wi: [0.3487429, 0.11624764, 0.9299811], wo: [-0.21566555, -0.107832775, -0.970495], eval: [12.673702, 12.673702, 12.673702], pdf: 28.5433 },
    EvalCase { bsdf: "dielectric_ggx", wi: [0.22792116, 0.34188172, -0.91168463], wo: [-0.51214755, -0.38411063, 0.76822126], eval: [2.3070493, 2.3070493, 2.3070493], pdf: 1.0363631 },
    EvalCase { bsdf: "dielectric_ggx", wi: [0.22792116, 0.34188172, -0.91168463], wo: [-0.38100037, -0.25400025, -0.8890009], eval: [0.048361424, 0.048361424, 0.048361424], pdf: 0.048561074 },
    EvalCase { bsdf: "dielectric_ggx", wi: [0.97618705, 0.0, 0.21693046], wo: [-0.94345635, 0.104828484, 0.31448546], eval: [0.38020682, 0.38020682, 0.38020682], pdf: 0.4282601 },
    EvalCase { bsdf: "dielectric_beckmann_plain", wi: [0.3487429, 0.11624764, 0.9299811], wo: [-0.48154342, 0.24077171, 0.84270096], eval: [0.011508218, 0.011508218, 0.010229527], pdf: 0.012735259 },
    EvalCase { bsdf: "dielectric_beckmann_plain", wi: [0.7442084, -0.24806947, 0.6201737], wo: [-0.63500065, 0.12700012, 0.76200074], eval: [0.03203464, 0.03203464, 0.028475238], pdf: 0.02934735 },
    EvalCase { bsdf: "dielectric_beckmann_plain", wi: [0.049927656, 0.019971063, 0.99855316], wo: [0.38411063, 0.51214755, 0.76822126], eval: [0.0039797123, 0.0039797123, 0.0035375224], pdf: 0.004343259 },
    EvalCase { bsdf: "dielectric_beckmann_plain", wi: [0.3487429, 0.11624764, 0.9299811], wo: [-0.21566555, -0.107832775, -0.970495], eval: [11.215537, 12.817757, 14.419976], pdf: 29.729248 },
    EvalCase { bsdf: "dielectric_beckmann_plain", wi: [0.22792116, 0.34188172, -0.91168463], wo: [-0.51214755, -0.38411063, 0.76822126], eval: [0.75289065, 0.86044645, 0.96800226], pdf: 0.6657139 },
    EvalCase { bsdf: "dielectric_beckmann_plain", wi: [0.22792116, 0.34188172, -0.91168463], wo: [-0.38100037, -0.25400025, -0.8890009], eval: [0.017648319, 0.017648319, 0.015687397], pdf: 0.019353434 },
    EvalCase { bsdf: "dielectric_beckmann_plain", wi: [0.97618705, 0.0, 0.21693046], wo: [-0.94345635, 0.104828484, 0.31448546], eval: [0.44831136, 0.44831136, 0.39849898], pdf: 0.37854743 },
    EvalCase { bsdf: "plastic_rough_ggx", wi: [0.3487429, 0.11624764, 0.9299811], wo: [-0.48154342, 0.24077171, 0.84270096], eval: [0.14677785, 0.08327047, 0.040932212], pdf: 0.29652837 },
    EvalCase { bsdf: "plastic_rough_ggx", wi: [0.7442084, -0.24806947, 0.6201737], wo: [-0.63500065, 0.12700012, 0.76200074], eval: [0.19918533, 0.14387773, 0.107006006], pdf: 0.5367237 },
    EvalCase { bsdf: "plastic_rough_ggx", wi: [0.049927656, 0.019971063, 0.99855316], wo: [0.38411063, 0.51214755, 0.76822126], eval: [0.119813025, 0.062142447, 0.023695393], pdf: 0.22971967 },
    EvalCase { bsdf: "plastic_rough_ggx", wi: [0.97618705, 0.0, 0.21693046], wo: [-0.94345635, 0.104828484, 0.31448546], eval: [0.46700174, 0.45024619, 0.43907583], pdf: 0.9754513 },
    EvalCase { bsdf: "plastic_rough_beckmann_nonlinear", wi: [0.3487429, 0.11624764, 0.9299811], wo: [-0.48154342, 0.24077171, 0.84270096], eval: [0.16728729, 0.09282679, 0.048032332], pdf: 0.298486 },
    EvalCase { bsdf: "plastic_rough_beckmann_nonlinear", wi: [0.7442084, -0.24806947, 0.6201737], wo: [-0.63500065, 0.12700012, 0.76200074], eval: [0.1879442, 0.12320115, 0.08425257], pdf: 0.37403336 },
    EvalCase { bsdf: "plastic_rough_beckmann_nonlinear", wi: [0.049927656, 0.019971063, 0.99855316], wo: [0.38411063, 0.51214755, 0.76822126], eval: [0.13675858, 0.06918123, 0.02852759], pdf: 0.24241276 },
    EvalCase { bsdf: "plastic_rough_beckmann_nonlinear", wi: [0.97618705, 0.0, 0.21693046], wo: [-0.94345635, 0.104828484, 0.31448546], eval: [0.5532488, 0.53341156, 0.5214777], pdf: 0.88201255 },
    EvalCase { bsdf: "plastic_smooth", wi: [0.3487429, 0.11624764, 0.9299811], wo: [-0.48154342, 0.24077171, 0.84270096], eval: [0.054415658, 0.13603914, 0.1904548], pdf: 0.24673434 },
    EvalCase { bsdf: "plastic_smooth", wi: [0.7442084, -0.24806947, 0.6201737], wo: [-0.63500065, 0.12700012, 0.76200074], eval: [0.047967546, 0.11991887, 0.1678864], pdf: 0.21356036 },
    EvalCase { bsdf: "plastic_smooth", wi: [0.049927656, 0.019971063, 0.99855316], wo: [0.38411063, 0.51214755, 0.76822126], eval: [0.049451143, 0.12362786, 0.173079], pdf: 0.22510043 },
    EvalCase { bsdf: "plastic_smooth", wi: [0.97618705, 0.0, 0.21693046], wo: [-0.94345635, 0.104828484, 0.31448546], eval: [0.012292789, 0.030731972, 0.04302476], pdf: 0.051077902 },
    EvalCase { bsdf: "plastic_smooth_nonlinear", wi: [0.3487429, 0.11624764, 0.9299811], wo: [-0.48154342, 0.24077171, 0.84270096], eval: [0.19371338, 0.06170932, 0.018700587], pdf: 0.23611432 },
    EvalCase { bsdf: "plastic_smooth_nonlinear", wi: [0.7442084, -0.24806947, 0.6201737], wo: [-0.63500065, 0.12700012, 0.76200074], eval: [0.1700288, 0.054164365, 0.01641414], pdf: 0.20431878 },
    EvalCase { bsdf: "plastic_smooth_nonlinear", wi: [0.049927656, 0.019971063, 0.99855316], wo: [0.38411063, 0.51214755, 0.76822126], eval: [0.1759355, 0.056046, 0.016984357], pdf: 0.21542604 },
    EvalCase { bsdf: "plastic_smooth_nonlinear", wi: [0.97618705, 0.0, 0.21693046], wo: [-0.94345635, 0.104828484, 0.31448546], eval: [0.0427265, 0.013610952, 0.0041247057], pdf: 0.051092975 },
    EvalCase { bsdf: "diffuse", wi: [0.3487429, 0.11624764, 0.9299811], wo: [-0.48154342, 0.24077171, 0.84270096], eval: [0.080472015, 0.16094403, 0.24141602], pdf: 0.26824003 },
    EvalCase { bsdf: "diffuse", wi: [0.7442084, -0.24806947, 0.6201737], wo: [-0.63500065, 0.12700012, 0.76200074], eval: [0.07276571, 0.14553142, 0.21829711], pdf: 0.24255235 },
    EvalCase { bsdf: "diffuse", wi: [0.049927656, 0.019971063, 0.99855316], wo: [0.38411063, 0.51214755, 0.76822126], eval: [0.07335973, 0.14671946, 0.22007917], pdf: 0.2445324 },
    EvalCase { bsdf: "diffuse", wi: [0.97618705, 0.0, 0.21693046], wo: [-0.94345635, 0.104828484, 0.31448546], eval: [0.03003115, 0.0600623, 0.09009344], pdf: 0.100103825 },
    EvalCase { bsdf: "principled_opaque", wi: [0.3487429, 0.11624764, 0.9299811], wo: [-0.48154342, 0.24077171, 0.84270096], eval: [0.20849332, 0.10952377, 0.06003899], pdf: 0.25052226 },
    EvalCase { bsdf: "principled_opaque", wi: [0.7442084, -0.24806947, 0.6201737], wo: [-0.63500065, 0.12700012, 0.76200074], eval: [0.6686938, 0.36378, 0.21132305], pdf: 1.1580435 },
    EvalCase { bsdf: "principled_opaque", wi: [0.049927656, 0.019971063, 0.99855316], wo: [0.38411063, 0.51214755, 0.76822126], eval: [0.14240061, 0.072713785, 0.037870374], pdf: 0.12923676 },
    EvalCase { bsdf: "principled_opaque", wi: [0.97618705, 0.0, 0.21693046], wo: [-0.94345635, 0.104828484, 0.31448546], eval: [0.45480058, 0.32982954, 0.26734406], pdf: 0.61007816 },
    EvalCase { bsdf: "principled_glass", wi: [0.3487429, 0.11624764, 0.9299811], wo: [-0.48154342, 0.24077171, 0.84270096], eval: [0.11801608, 0.09355826, 0.06910042], pdf: 0.16159363 },
    EvalCase { bsdf: "principled_glass", wi: [0.7442084, -0.24806947, 0.6201737], wo: [-0.63500065, 0.12700012, 0.76200074], eval: [0.3635603, 0.30235836, 0.24115638], pdf: 0.84614086 },
    EvalCase { bsdf: "principled_glass", wi: [0.049927656, 0.019971063, 0.99855316], wo: [0.38411063, 0.51214755, 0.76822126], eval: [0.08329393, 0.065012865, 0.046731792], pdf: 0.076603085 },
    EvalCase { bsdf: "principled_glass", wi: [0.3487429, 0.11624764, 0.9299811], wo: [-0.21566555, -0.107832775, -0.970495], eval: [12.16779, 10.730984, 9.069336], pdf: 19.830875 },
    EvalCase { bsdf: "principled_glass", wi: [0.22792116, 0.34188172, -0.91168463], wo: [-0.51214755, -0.38411063, 0.76822126], eval: [0.23605517, 0.2081811, 0.17594513], pdf: 0.21946831 },
    EvalCase { bsdf: "principled_glass", wi: [0.22792116, 0.34188172, -0.91168463], wo: [-0.38100037, -0.25400025, -0.8890009], eval: [0.047106456, 0.047106456, 0.047106456], pdf: 0.08728101 },
    EvalCase { bsdf: "principled_glass", wi: [0.97618705, 0.0, 0.21693046], wo: [-0.94345635, 0.104828484, 0.31448546], eval: [0.37778354, 0.35318077, 0.3285779], pdf: 0.54279786 },
    EvalCase { bsdf: "thin_glossy", wi: [0.3487429, 0.11624764, 0.9299811], wo: [-0.48154342, 0.24077171, 0.84270096], eval: [0.049952947, 0.03209021, 0.020181723], pdf: 0.13280745 },
    EvalCase { bsdf: "thin_glossy", wi: [0.3487429, 0.11624764, 0.9299811], wo: [-0.21566555, -0.107832775, -0.970495], eval: [3.7216265, 2.3260167, 1.39561], pdf: 2.416948 },
    EvalCase { bsdf: "thin_glossy", wi: [0.7442084, -0.24806947, 0.6201737], wo: [-0.48154342, 0.24077171, 0.84270096], eval: [0.08902887, 0.06421304, 0.04766915], pdf: 0.61311746 },
    EvalCase { bsdf: "thin_glossy", wi: [0.7442084, -0.24806947, 0.6201737], wo: [-0.38100037, -0.25400025, -0.8890009], eval: [0.039912652, 0.024945408, 0.014967244], pdf: 0.04765671 },
    EvalCase { bsdf: "thin_glossy", wi: [0.22792116, 0.34188172, -0.91168463], wo: [-0.51214755, -0.38411063, 0.76822126], eval: [0.31896153, 0.19935094, 0.11961057], pdf: 0.22446509 },
    EvalCase { bsdf: "thin_glossy", wi: [0.22792116, 0.34188172, -0.91168463], wo: [-0.38100037, -0.25400025, -0.8890009], eval: [0.087017305, 0.0619483, 0.045235626], pdf: 0.6615808 },
    EvalCase { bsdf: "thin_glossy", wi: [0.22792116, 0.34188172, -0.91168463], wo: [-0.21566555, -0.107832775, -0.970495], eval: [0.06708706, 0.04493342, 0.030164331], pdf: 0.3132423 },
    EvalCase { bsdf: "thin_glossy", wi: [0.97618705, 0.0, 0.21693046], wo: [-0.48154342, 0.24077171, 0.84270096], eval: [0.058201943, 0.038348112, 0.02511223], pdf: 0.1306155 },
    EvalCase { bsdf: "thin_glossy", wi: [0.97618705, 0.0, 0.21693046], wo: [-0.21566555, -0.107832775, -0.970495], eval: [0.053755663, 0.03359729, 0.020158375], pdf: 0.058648597 },
    EvalCase { bsdf: "thin_diffuse", wi: [0.3487429, 0.11624764, 0.9299811], wo: [-0.48154342, 0.24077171, 0.84270096], eval: [0.028167631, 0.056334633, 0.08450163], pdf: 0.056899406 },
    EvalCase { bsdf: "thin_diffuse", wi: [0.3487429, 0.11624764, 0.9299811], wo: [-0.21566555, -0.107832775, -0.970495], eval: [0.06023904, 0.12047808, 0.18071711], pdf: 0.24339007 },
    EvalCase { bsdf: "thin_diffuse", wi: [0.7442084, -0.24806947, 0.6201737], wo: [-0.48154342, 0.24077171, 0.84270096], eval: [0.028325697, 0.05655247, 0.08477923], pdf: 0.056899406 },
    EvalCase { bsdf: "thin_diffuse", wi: [0.7442084, -0.24806947, 0.6201737], wo: [-0.38100037, -0.25400025, -0.8890009], eval: [0.05518067, 0.11036134, 0.16554199], pdf: 0.22295219 },
    EvalCase { bsdf: "thin_diffuse", wi: [0.22792116, 0.34188172, -0.91168463], wo: [-0.51214755, -0.38411063, 0.76822126], eval: [0.047683824, 0.09536765, 0.14305146], pdf: 0.1926619 },
    EvalCase { bsdf: "thin_diffuse", wi: [0.22792116, 0.34188172, -0.91168463], wo: [-0.38100037, -0.25400025, -0.8890009], eval: [0.029713832, 0.059426926, 0.08914003], pdf: 0.06002559 },
    EvalCase { bsdf: "thin_diffuse", wi: [0.22792116, 0.34188172, -0.91168463], wo: [-0.21566555, -0.107832775, -0.970495], eval: [0.032436576, 0.064873114, 0.09730965], pdf: 0.0655281 },
    EvalCase { bsdf: "thin_diffuse", wi: [0.97618705, 0.0, 0.21693046], wo: [-0.48154342, 0.24077171, 0.84270096], eval: [0.029097166, 0.057253342, 0.085409515], pdf: 0.056899406 },
    EvalCase { bsdf: "thin_diffuse", wi: [0.97618705, 0.0, 0.21693046], wo: [-0.21566555, -0.107832775, -0.970495], eval: [0.06023904, 0.12047808, 0.18071711], pdf: 0.24339007 },
];
#[rustfmt::skip]
const SAMPLE_CASES: &[SampleCase] = &[
    SampleCase { bsdf: "conductor_ggx", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.3, u2: (0.2, 0.7), wo: [-0.5742825, 0.15223034, 0.804379], pdf: 0.48543435, weight: [0.94028246, 0.6083096, 0.5183414] },
    SampleCase { bsdf: "conductor_ggx", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.9, u2: (0.55, 0.1), wo: [0.5243852, 0.088561885, 0.8468632], pdf: 0.10165765, weight: [0.94365144, 0.61042565, 0.51975316] },
    SampleCase { bsdf: "conductor_ggx", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.05, u2: (0.8, 0.45), wo: [-0.10844568, -0.46862036, 0.8767179], pdf: 0.40276468, weight: [0.94549036, 0.61162984, 0.5209254] },
    SampleCase { bsdf: "conductor_ggx", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.6, u2: (0.33, 0.91), wo: [-0.84611136, -0.09905299, 0.52372116], pdf: 0.22311322, weight: [0.90007406, 0.58284897, 0.4979445] },
    SampleCase { bsdf: "conductor_ggx", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.3, u2: (0.2, 0.7), wo: [-0.6817857, 0.45650882, 0.5716362], pdf: 0.7834335, weight: [0.90800416, 0.5917373, 0.50969267] },
    SampleCase { bsdf: "conductor_ggx", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.9, u2: (0.55, 0.1), wo: [0.33602825, -0.21640457, 0.91665375], pdf: 0.061491393, weight: [0.9478943, 0.6131717, 0.52212] },
    SampleCase { bsdf: "conductor_ggx", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.05, u2: (0.8, 0.45), wo: [-0.6746677, -0.12135793, 0.7280765], pdf: 0.46070835, weight: [0.93171245, 0.60429806, 0.5176506] },
    SampleCase { bsdf: "conductor_ggx", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.6, u2: (0.33, 0.91), wo: [-0.8834509, 0.38578495, 0.26586524], pdf: 0.6367623, weight: [0.76259536, 0.5075642, 0.44393167] },
    SampleCase { bsdf: "conductor_beckmann_aniso_plain", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.3, u2: (0.2, 0.7), wo: [-0.39954585, -0.4289583, 0.81015915], pdf: 0.9449254, weight: [0.3612637, 0.43845397, 0.48301053] },
    SampleCase { bsdf: "conductor_beckmann_aniso_plain", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.9, u2: (0.55, 0.1), wo: [-0.07592035, 0.28018677, 0.9569386], pdf: 0.50530934, weight: [0.40323326, 0.49025157, 0.54038733] },
    SampleCase { bsdf: "conductor_beckmann_aniso_plain", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.05, u2: (0.8, 0.45), wo: [-0.73385626, 0.1340142, 0.6659543], pdf: 0.269961, weight: [0.3479733, 0.42134917, 0.46379504] },
    SampleCase { bsdf: "conductor_beckmann_aniso_plain", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.6, u2: (0.33, 0.91), wo: [-0.15127335, -0.36688337, 0.917885], pdf: 0.7428384, weight: [0.38195935, 0.46418884, 0.51158834] },
    SampleCase { bsdf: "conductor_beckmann_aniso_plain", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.3, u2: (0.2, 0.7), wo: [-0.78054976, 0.024375014, 0.62461823], pdf: 1.3209459, weight: [0.3963391, 0.47070587, 0.51413625] },
    SampleCase { bsdf: "conductor_beckmann_aniso_plain", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.9, u2: (0.55, 0.1), wo: [-0.5607594, 0.51463646, 0.6486125], pdf: 0.7514885, weight: [0.4149056, 0.49434203, 0.5407019] },
    SampleCase { bsdf: "conductor_beckmann_aniso_plain", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.05, u2: (0.8, 0.45), wo: [-0.9232431, 0.3644133, 0.12175816], pdf: 0.5807007, weight: [0.22932872, 0.2556738, 0.2699848] },
    SampleCase { bsdf: "conductor_beckmann_aniso_plain", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.6, u2: (0.33, 0.91), wo: [-0.5920098, 0.054893326, 0.80405915], pdf: 0.96379316, weight: [0.44639397, 0.5361662, 0.58839023] },
    SampleCase { bsdf: "conductor_beckmann", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.3, u2: (0.2, 0.7), wo: [-0.0010309197, -0.18720657, 0.9823201], pdf: 0.8443856, weight: [0.95193774, 0.6157866, 0.5243383] },
    SampleCase { bsdf: "conductor_beckmann", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.9, u2: (0.55, 0.1), wo: [-0.49141136, 0.25699756, 0.83214605], pdf: 0.6647846, weight: [0.95176697, 0.61571217, 0.5245273] },
    SampleCase { bsdf: "conductor_beckmann", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.05, u2: (0.8, 0.45), wo: [-0.5838219, -0.1541664, 0.7971101], pdf: 1.048832, weight: [0.9516195, 0.6156702, 0.52471274] },
    SampleCase { bsdf: "conductor_beckmann", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.6, u2: (0.33, 0.91), wo: [-0.058726083, -0.47171962, 0.8797907], pdf: 0.55463254, weight: [0.95186603, 0.615751, 0.5244137] },
    SampleCase { bsdf: "conductor_beckmann", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.3, u2: (0.2, 0.7), wo: [-0.5303478, 0.03340393, 0.84712213], pdf: 1.1280488, weight: [0.9505851, 0.615765, 0.52640796] },
    SampleCase { bsdf: "conductor_beckmann", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.9, u2: (0.55, 0.1), wo: [-0.6381912, 0.5005223, 0.58496946], pdf: 0.9940748, weight: [0.9485477, 0.6176314, 0.53154254] },
    SampleCase { bsdf: "conductor_beckmann", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.05, u2: (0.8, 0.45), wo: [-0.8434275, 0.30600408, 0.44157845], pdf: 1.7423671, weight: [0.9467184, 0.6213699, 0.53846794] },
    SampleCase { bsdf: "conductor_beckmann", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.6, u2: (0.33, 0.91), wo: [-0.6989237, -0.09892982, 0.70832086], pdf: 0.7736107, weight: [0.949746, 0.6162678, 0.52823156] },
    SampleCase { bsdf: "dielectric_ggx_aniso_plain", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.3, u2: (0.2, 0.7), wo: [-0.21398626, -0.012360128, -0.9767585], pdf: 18.821589, weight: [0.40406984, 0.40406984, 0.40406984] },
    SampleCase { bsdf: "dielectric_ggx_aniso_plain", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.9, u2: (0.55, 0.1), wo: [-0.28755227, -0.15391554, -0.94531673], pdf: 7.5753, weight: [0.45730394, 0.45730394, 0.45730394] },
    SampleCase { bsdf: "dielectric_ggx_aniso_plain", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.05, u2: (0.8, 0.45), wo: [-0.875965, 0.18353586, 0.446094], pdf: 0.004116805, weight: [0.84636647, 0.84636647, 0.84636647] },
    SampleCase { bsdf: "dielectric_ggx_aniso_plain", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.6, u2: (0.33, 0.91), wo: [-0.26875302, -0.027357573, -0.96282053], pdf: 14.595204, weight: [0.42933437, 0.42933437, 0.42933437] },
    SampleCase { bsdf: "dielectric_ggx_aniso_plain", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.3, u2: (0.2, 0.7), wo: [-0.4670454, 0.23861825, -0.85142815], pdf: 10.830977, weight: [0.42126673, 0.42126673, 0.42126673] },
    SampleCase { bsdf: "dielectric_ggx_aniso_plain", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.9, u2: (0.55, 0.1), wo: [-0.56071806, 0.059853073, -0.82584065], pdf: 4.045624, weight: [0.46169063, 0.46169063, 0.46169063] },
    SampleCase { bsdf: "dielectric_ggx_aniso_plain", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.6, u2: (0.33, 0.91), wo: [-0.5329875, 0.21764487, -0.81765217], pdf: 9.358627, weight: [0.49124023, 0.49124023, 0.49124023] },
    SampleCase { bsdf: "dielectric_ggx_aniso_plain", wi: [0.22792116, 0.34188172, -0.91168463], u: 0.3, u2: (0.2, 0.7), wo: [-0.3344194, -0.4323722, 0.8373877], pdf: 7.6774445, weight: [2.5206103, 2.5206103, 2.5206103] },
    SampleCase { bsdf: "dielectric_ggx_aniso_plain", wi: [0.22792116, 0.34188172, -0.91168463], u: 0.9, u2: (0.55, 0.1), wo: [-0.4913988, -0.67688024, -0.5480515], pdf: 0.33619234, weight: [0.8218018, 0.8218018, 0.8218018] },
    SampleCase { bsdf: "dielectric_ggx_aniso_plain", wi: [0.22792116, 0.34188172, -0.91168463], u: 0.05, u2: (0.8, 0.45), wo: [0.36605752, -0.6796236, -0.63569945], pdf: 0.0054140366, weight: [0.97319925, 0.97319925, 0.97319925] },
    SampleCase { bsdf: "dielectric_ggx_aniso_plain", wi: [0.22792116, 0.34188172, -0.91168463], u: 0.6, u2: (0.33, 0.91), wo: [-0.42662385, -0.4457552, 0.7869527], pdf: 3.9104133, weight: [2.3939018, 2.3939018, 2.3939018] },
    SampleCase { bsdf: "conductor_ggx_aniso", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.3, u2: (0.2, 0.7), wo: [-0.5155496, 0.082522586, 0.85287666], pdf: 0.76407534, weight: [0.94953775, 0.61427325, 0.52331704] },
    SampleCase { bsdf: "conductor_ggx_aniso", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.9, u2: (0.55, 0.1), wo: [0.009158712, 0.41594508, 0.90934366], pdf: 0.18071252, weight: [0.945916, 0.6118913, 0.5210191] },
    SampleCase { bsdf: "conductor_ggx_aniso", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.05, u2: (0.8, 0.45), wo: [-0.18701138, -0.42668587, 0.88485366], pdf: 0.6911031, weight: [0.94492334, 0.6112658, 0.52063286] },
    SampleCase { bsdf: "conductor_ggx_aniso", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.6, u2: (0.33, 0.91), wo: [-0.6369419, -0.33760512, 0.69305664], pdf: 0.27537718, weight: [0.9401986, 0.6084086, 0.51890564] },
    SampleCase { bsdf: "conductor_ggx_aniso", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.3, u2: (0.2, 0.7), wo: [-0.6987217, 0.4792068, 0.53117675], pdf: 1.3395499, weight: [0.91717505, 0.5985757, 0.51628536] },
    SampleCase { bsdf: "conductor_ggx_aniso", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.9, u2: (0.55, 0.1), wo: [-0.42843533, -0.4362991, 0.7912562], pdf: 0.15063371, weight: [0.94090694, 0.60903597, 0.51983273] },
    SampleCase { bsdf: "conductor_ggx_aniso", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.05, u2: (0.8, 0.45), wo: [-0.78585964, -0.10003054, 0.610261], pdf: 0.9711566, weight: [0.93951523, 0.6109382, 0.5250381] },
    SampleCase { bsdf: "conductor_ggx_aniso", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.6, u2: (0.33, 0.91), wo: [-0.8080544, 0.5100896, 0.29471472], pdf: 0.80142105, weight: [0.84423935, 0.5591717, 0.48761523] },
    SampleCase { bsdf: "dielectric_ggx", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.3, u2: (0.2, 0.7), wo: [-0.19240782, -0.122809276, -0.9736001], pdf: 17.023878, weight: [0.44406343, 0.44406343, 0.44406343] },
    SampleCase { bsdf: "dielectric_ggx", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.9, u2: (0.55, 0.1), wo: [-0.35448915, -0.10599726, -0.9290328], pdf: 4.849764, weight: [0.44334844, 0.44334844, 0.44334844] },
    SampleCase { bsdf: "dielectric_ggx", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.05, u2: (0.8, 0.45), wo: [-0.2688719, -0.021471515, -0.9629366], pdf: 16.164759, weight: [0.4439009, 0.4439009, 0.4439009] },
    SampleCase { bsdf: "dielectric_ggx", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.6, u2: (0.33, 0.91), wo: [-0.12333861, -0.08064767, -0.98908216], pdf: 5.24897, weight: [0.44429046, 0.44429046, 0.44429046] },
    SampleCase { bsdf: "dielectric_ggx", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.3, u2: (0.2, 0.7), wo: [-0.5101943, 0.09924254, -0.85431415], pdf: 10.573202, weight: [0.44190335, 0.44190335, 0.44190335] },
    SampleCase { bsdf: "dielectric_ggx", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.9, u2: (0.55, 0.1), wo: [-0.65791345, 0.23514728, -0.7154408], pdf: 2.452122, weight: [0.43801206, 0.43801206, 0.43801206] },
    SampleCase { bsdf: "dielectric_ggx", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.05, u2: (0.8, 0.45), wo: [-0.7025847, -0.044981625, 0.71017694], pdf: 0.03632213, weight: [0.98509884, 0.98509884, 0.98509884] },
    SampleCase { bsdf: "dielectric_ggx", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.6, u2: (0.33, 0.91), wo: [-0.42364472, 0.097797826, -0.90053356], pdf: 4.298941, weight: [0.4428374, 0.4428374, 0.4428374] },
    SampleCase { bsdf: "dielectric_ggx", wi: [0.22792116, 0.34188172, -0.91168463], u: 0.3, u2: (0.2, 0.7), wo: [-0.44443074, -0.4916765, 0.74882287], pdf: 3.9710515, weight: [2.223114, 2.223114, 2.223114] },
    SampleCase { bsdf: "dielectric_ggx", wi: [0.22792116, 0.34188172, -0.91168463], u: 0.9, u2: (0.55, 0.1), wo: [-0.22097914, -0.36319473, 0.9051287], pdf: 2.0572002, weight: [2.242297, 2.242297, 2.242297] },
    SampleCase { bsdf: "dielectric_ggx", wi: [0.22792116, 0.34188172, -0.91168463], u: 0.05, u2: (0.8, 0.45), wo: [-0.23665087, -0.54745543, 0.80267626], pdf: 4.851967, weight: [2.2309182, 2.2309182, 2.2309182] },
    SampleCase { bsdf: "dielectric_ggx", wi: [0.22792116, 0.34188172, -0.91168463], u: 0.6, u2: (0.33, 0.91), wo: [-0.5366421, -0.65429544, 0.53283477], pdf: 0.2715809, weight: [2.1676972, 2.1676972, 2.1676972] },
    SampleCase { bsdf: "dielectric_beckmann_plain", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.3, u2: (0.2, 0.7), wo: [-0.25041234, -0.051086474, -0.96679044], pdf: 36.205723, weight: [0.3824668, 0.43710488, 0.491743] },
    SampleCase { bsdf: "dielectric_beckmann_plain", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.9, u2: (0.55, 0.1), wo: [-0.31496358, -0.12573, -0.94073904], pdf: 27.14038, weight: [0.43598986, 0.49827412, 0.5605584] },
    SampleCase { bsdf: "dielectric_beckmann_plain", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.05, u2: (0.8, 0.45), wo: [-0.1599614, -0.1206277, -0.97972506], pdf: 8.092374, weight: [0.34748796, 0.39712906, 0.4467702] },
    SampleCase { bsdf: "dielectric_beckmann_plain", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.6, u2: (0.33, 0.91), wo: [-0.30286396, -0.06160619, -0.9510405], pdf: 35.872395, weight: [0.41461533, 0.47384608, 0.5330768] },
    SampleCase { bsdf: "dielectric_beckmann_plain", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.3, u2: (0.2, 0.7), wo: [-0.54406047, 0.23420607, -0.80569583], pdf: 17.716925, weight: [0.39628747, 0.45289996, 0.5095124] },
    SampleCase { bsdf: "dielectric_beckmann_plain", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.9, u2: (0.55, 0.1), wo: [-0.62742823, 0.13720573, -0.766491], pdf: 14.011173, weight: [0.47709072, 0.5452465, 0.6134023] },
    SampleCase { bsdf: "dielectric_beckmann_plain", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.6, u2: (0.33, 0.91), wo: [-0.6090676, 0.21793991, -0.76258695], pdf: 21.49953, weight: [0.49186736, 0.56213415, 0.6324009] },
    SampleCase { bsdf: "dielectric_beckmann_plain", wi: [0.22792116, 0.34188172, -0.91168463], u: 0.3, u2: (0.2, 0.7), wo: [-0.28784794, -0.40765348, 0.86658084], pdf: 21.26166, weight: [1.3150568, 1.502922, 1.6907873] },
    SampleCase { bsdf: "dielectric_beckmann_plain", wi: [0.22792116, 0.34188172, -0.91168463], u: 0.9, u2: (0.55, 0.1), wo: [-0.40531737, -0.5289424, 0.7456124], pdf: 3.9150746, weight: [1.0966592, 1.2533249, 1.4099904] },
    SampleCase { bsdf: "dielectric_beckmann_plain", wi: [0.22792116, 0.34188172, -0.91168463], u: 0.05, u2: (0.8, 0.45), wo: [-0.17085613, -0.49768278, 0.85036474], pdf: 4.418012, weight: [1.2961874, 1.4813571, 1.6665267] },
    SampleCase { bsdf: "dielectric_beckmann_plain", wi: [0.22792116, 0.34188172, -0.91168463], u: 0.6, u2: (0.33, 0.91), wo: [-0.364485, -0.41576895, 0.8332389], pdf: 12.915685, weight: [1.2358232, 1.4123694, 1.5889156] },
    SampleCase { bsdf: "plastic_rough_ggx", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.3, u2: (0.2, 0.7), wo: [-0.5196153, 0.29999998, 0.8], pdf: 0.2644416, weight: [0.50461453, 0.27734765, 0.12583642] },
    SampleCase { bsdf: "plastic_rough_ggx", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.9, u2: (0.55, 0.1), wo: [0.07841378, -0.79614776, 0.6], pdf: 0.17475182, weight: [0.5146489, 0.2636534, 0.09632306] },
    SampleCase { bsdf: "plastic_rough_ggx", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.05, u2: (0.8, 0.45), wo: [-0.19948576, -0.35832348, 0.9120362], pdf: 0.3610511, weight: [0.47710302, 0.28601155, 0.15861726] },
    SampleCase { bsdf: "plastic_rough_ggx", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.6, u2: (0.33, 0.91), wo: [-0.2623405, 0.77690256, 0.5723635], pdf: 0.16510014, weight: [0.5133185, 0.26140606, 0.09346446] },
    SampleCase { bsdf: "plastic_rough_ggx", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.3, u2: (0.2, 0.7), wo: [-0.5196153, 0.29999998, 0.8], pdf: 0.43645987, weight: [0.3985698, 0.26507542, 0.17607914] },
    SampleCase { bsdf: "plastic_rough_ggx", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.9, u2: (0.55, 0.1), wo: [0.07841378, -0.79614776, 0.6], pdf: 0.15766679, weight: [0.5433597, 0.2736547, 0.0938514] },
    SampleCase { bsdf: "plastic_rough_ggx", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.05, u2: (0.8, 0.45), wo: [-0.7242677, 0.025622329, 0.68904257], pdf: 0.39101654, weight: [0.405074, 0.27827248, 0.19373815] },
    SampleCase { bsdf: "plastic_rough_ggx", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.6, u2: (0.33, 0.91), wo: [-0.2623405, 0.77690256, 0.5723635], pdf: 0.15861642, weight: [0.52646226, 0.2722536, 0.10278114] },
    SampleCase { bsdf: "plastic_rough_beckmann_nonlinear", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.3, u2: (0.2, 0.7), wo: [-0.5196153, 0.29999998, 0.8], pdf: 0.2765131, weight: [0.56063443, 0.3057983, 0.1524922] },
    SampleCase { bsdf: "plastic_rough_beckmann_nonlinear", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.9, u2: (0.55, 0.1), wo: [0.07841378, -0.79614776, 0.6], pdf: 0.18088299, weight: [0.5523299, 0.26868936, 0.098054945] },
    SampleCase { bsdf: "plastic_rough_beckmann_nonlinear", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.05, u2: (0.8, 0.45), wo: [-0.62093174, -0.15927985, 0.7675113], pdf: 0.28719434, weight: [0.55718726, 0.32249695, 0.18131033] },
    SampleCase { bsdf: "plastic_rough_beckmann_nonlinear", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.6, u2: (0.33, 0.91), wo: [-0.2623405, 0.77690256, 0.5723635], pdf: 0.1694885, weight: [0.54933864, 0.26248053, 0.08991046] },
    SampleCase { bsdf: "plastic_rough_beckmann_nonlinear", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.3, u2: (0.2, 0.7), wo: [-0.5196153, 0.29999998, 0.8], pdf: 0.3670375, weight: [0.5048522, 0.31900474, 0.20720135] },
    SampleCase { bsdf: "plastic_rough_beckmann_nonlinear", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.9, u2: (0.55, 0.1), wo: [0.07841378, -0.79614776, 0.6], pdf: 0.16620263, weight: [0.56332016, 0.26449412, 0.08472433] },
    SampleCase { bsdf: "plastic_rough_beckmann_nonlinear", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.05, u2: (0.8, 0.45), wo: [-0.85029495, 0.312752, 0.42330188], pdf: 0.27982193, weight: [0.57181877, 0.45338428, 0.3821357] },
    SampleCase { bsdf: "plastic_rough_beckmann_nonlinear", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.6, u2: (0.33, 0.91), wo: [-0.2623405, 0.77690256, 0.5723635], pdf: 0.16481821, weight: [0.5537064, 0.26814958, 0.09636237] },
    SampleCase { bsdf: "plastic_smooth", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.3, u2: (0.2, 0.7), wo: [-0.5196153, 0.29999998, 0.8], pdf: 0.23423195, weight: [0.22015914, 0.5503979, 0.770557] },
    SampleCase { bsdf: "plastic_smooth", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.9, u2: (0.55, 0.1), wo: [0.07841378, -0.79614776, 0.6], pdf: 0.17567396, weight: [0.21545903, 0.5386476, 0.7541066] },
    SampleCase { bsdf: "plastic_smooth", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.05, u2: (0.8, 0.45), wo: [-0.3487429, -0.11624764, 0.9299811], pdf: 0.080173336, weight: [0.48751217, 0.48751217, 0.48751217] },
    SampleCase { bsdf: "plastic_smooth", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.6, u2: (0.33, 0.91), wo: [-0.2623405, 0.77690256, 0.5723635], pdf: 0.16758226, weight: [0.21421249, 0.5355312, 0.7497437] },
    SampleCase { bsdf: "plastic_smooth", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.3, u2: (0.2, 0.7), wo: [-0.5196153, 0.29999998, 0.8], pdf: 0.22421014, weight: [0.22509487, 0.56273717, 0.787832] },
    SampleCase { bsdf: "plastic_smooth", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.9, u2: (0.55, 0.1), wo: [0.07841378, -0.79614776, 0.6], pdf: 0.1681576, weight: [0.22028938, 0.55072343, 0.7710128] },
    SampleCase { bsdf: "plastic_smooth", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.05, u2: (0.8, 0.45), wo: [-0.7442084, 0.24806947, 0.6201737], pdf: 0.11952885, weight: [0.4984416, 0.4984416, 0.4984416] },
    SampleCase { bsdf: "plastic_smooth", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.6, u2: (0.33, 0.91), wo: [-0.2623405, 0.77690256, 0.5723635], pdf: 0.16041212, weight: [0.2190149, 0.54753727, 0.7665521] },
    SampleCase { bsdf: "plastic_smooth_nonlinear", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.3, u2: (0.2, 0.7), wo: [-0.5196153, 0.29999998, 0.8], pdf: 0.22415005, weight: [0.81869906, 0.2608047, 0.07903508] },
    SampleCase { bsdf: "plastic_smooth_nonlinear", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.9, u2: (0.55, 0.1), wo: [0.07841378, -0.79614776, 0.6], pdf: 0.16811255, weight: [0.7986915, 0.2544311, 0.07710361] },
    SampleCase { bsdf: "plastic_smooth_nonlinear", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.05, u2: (0.8, 0.45), wo: [-0.3487429, -0.11624764, 0.9299811], pdf: 0.11976479, weight: [0.564906, 0.564906, 0.564906] },
    SampleCase { bsdf: "plastic_smooth_nonlinear", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.6, u2: (0.33, 0.91), wo: [-0.2623405, 0.77690256, 0.5723635], pdf: 0.16036913, weight: [0.79356706, 0.25279868, 0.0766089] },
    SampleCase { bsdf: "plastic_smooth_nonlinear", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.3, u2: (0.2, 0.7), wo: [-0.5196153, 0.29999998, 0.8], pdf: 0.21450771, weight: [0.83431464, 0.2657792, 0.080542564] },
    SampleCase { bsdf: "plastic_smooth_nonlinear", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.9, u2: (0.55, 0.1), wo: [0.07841378, -0.79614776, 0.6], pdf: 0.16088077, weight: [0.8139254, 0.25928402, 0.07857424] },
    SampleCase { bsdf: "plastic_smooth_nonlinear", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.05, u2: (0.8, 0.45), wo: [-0.7442084, 0.24806947, 0.6201737], pdf: 0.15763022, weight: [0.57568073, 0.57568073, 0.57568073] },
    SampleCase { bsdf: "plastic_smooth_nonlinear", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.6, u2: (0.33, 0.91), wo: [-0.2623405, 0.77690256, 0.5723635], pdf: 0.15347047, weight: [0.8087032, 0.25762042, 0.078070104] },
    SampleCase { bsdf: "diffuse", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.3, u2: (0.2, 0.7), wo: [-0.5196153, 0.29999998, 0.8], pdf: 0.2546479, weight: [0.3, 0.6, 0.9] },
    SampleCase { bsdf: "diffuse", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.9, u2: (0.55, 0.1), wo: [0.07841378, -0.79614776, 0.6], pdf: 0.19098593, weight: [0.3, 0.6, 0.9] },
    SampleCase { bsdf: "diffuse", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.05, u2: (0.8, 0.45), wo: [0.59486693, -0.07831574, 0.8], pdf: 0.2546479, weight: [0.3, 0.6, 0.9] },
    SampleCase { bsdf: "diffuse", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.6, u2: (0.33, 0.91), wo: [-0.2623405, 0.77690256, 0.5723635], pdf: 0.18218896, weight: [0.3, 0.6, 0.9] },
    SampleCase { bsdf: "diffuse", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.3, u2: (0.2, 0.7), wo: [-0.5196153, 0.29999998, 0.8], pdf: 0.2546479, weight: [0.3, 0.6, 0.9] },
    SampleCase { bsdf: "diffuse", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.9, u2: (0.55, 0.1), wo: [0.07841378, -0.79614776, 0.6], pdf: 0.19098593, weight: [0.3, 0.6, 0.9] },
    SampleCase { bsdf: "diffuse", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.05, u2: (0.8, 0.45), wo: [0.59486693, -0.07831574, 0.8], pdf: 0.2546479, weight: [0.3, 0.6, 0.9] },
    SampleCase { bsdf: "diffuse", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.6, u2: (0.33, 0.91), wo: [-0.2623405, 0.77690256, 0.5723635], pdf: 0.18218896, weight: [0.3, 0.6, 0.9] },
    SampleCase { bsdf: "principled_opaque", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.3, u2: (0.2, 0.7), wo: [-0.5196153, 0.29999998, 0.8], pdf: 0.1871418, weight: [0.9265469, 0.48137203, 0.25878462] },
    SampleCase { bsdf: "principled_opaque", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.9, u2: (0.55, 0.1), wo: [0.2873971, -0.08529523, 0.9540061], pdf: 0.30830193, weight: [0.82523084, 0.42745838, 0.22857219] },
    SampleCase { bsdf: "principled_opaque", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.05, u2: (0.8, 0.45), wo: [0.59486693, -0.07831574, 0.8], pdf: 0.1542132, weight: [1.0434879, 0.53138655, 0.2753359] },
    SampleCase { bsdf: "principled_opaque", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.6, u2: (0.33, 0.91), wo: [-0.7584201, -0.07880341, 0.6469843], pdf: 0.42660204, weight: [0.66817975, 0.35118335, 0.19268523] },
    SampleCase { bsdf: "principled_opaque", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.3, u2: (0.2, 0.7), wo: [-0.5196153, 0.29999998, 0.8], pdf: 1.1947277, weight: [0.5939991, 0.31891027, 0.1813659] },
    SampleCase { bsdf: "principled_opaque", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.9, u2: (0.55, 0.1), wo: [-0.02280428, 0.13916297, 0.9900071], pdf: 0.24521442, weight: [0.94278044, 0.4835688, 0.253963] },
    SampleCase { bsdf: "principled_opaque", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.05, u2: (0.8, 0.45), wo: [0.59486693, -0.07831574, 0.8], pdf: 0.114340305, weight: [1.2900882, 0.65001976, 0.3299855] },
    SampleCase { bsdf: "principled_opaque", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.6, u2: (0.33, 0.91), wo: [-0.89509124, 0.30335146, 0.3267868], pdf: 0.9931438, weight: [0.55995613, 0.3317627, 0.21766607] },
    SampleCase { bsdf: "principled_glass", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.3, u2: (0.2, 0.7), wo: [-0.22512235, -0.09501922, -0.96968615], pdf: 57.29701, weight: [0.61357576, 0.541123, 0.45733234] },
    SampleCase { bsdf: "principled_glass", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.9, u2: (0.55, 0.1), wo: [-0.107001044, -0.060664333, 0.9924066], pdf: 0.49476552, weight: [0.4914115, 0.39818123, 0.30495095] },
    SampleCase { bsdf: "principled_glass", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.05, u2: (0.8, 0.45), wo: [0.59486693, -0.07831574, 0.8], pdf: 0.07178805, weight: [1.1701977, 0.91132396, 0.6524502] },
    SampleCase { bsdf: "principled_glass", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.6, u2: (0.33, 0.91), wo: [-0.20026161, -0.0806622, -0.97641635], pdf: 15.764768, weight: [0.61359394, 0.541139, 0.4573459] },
    SampleCase { bsdf: "principled_glass", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.3, u2: (0.2, 0.7), wo: [-0.51168257, 0.14562352, -0.84674364], pdf: 31.936995, weight: [0.6131649, 0.54076064, 0.45702615] },
    SampleCase { bsdf: "principled_glass", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.9, u2: (0.55, 0.1), wo: [-0.5459479, 0.16111827, 0.82218105], pdf: 0.4788662, weight: [0.48366383, 0.39626306, 0.30886236] },
    SampleCase { bsdf: "principled_glass", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.05, u2: (0.8, 0.45), wo: [0.59486693, -0.07831574, 0.8], pdf: 0.068928994, weight: [1.2053816, 0.93794245, 0.6705032] },
    SampleCase { bsdf: "principled_glass", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.6, u2: (0.33, 0.91), wo: [-0.4777778, 0.14259489, -0.8668305], pdf: 9.975979, weight: [0.6132441, 0.5408305, 0.4570852] },
    SampleCase { bsdf: "principled_glass", wi: [0.22792116, 0.34188172, -0.91168463], u: 0.3, u2: (0.2, 0.7), wo: [-0.36471227, -0.49186215, 0.7906053], pdf: 44.079674, weight: [1.0757823, 0.94875085, 0.8018407] },
    SampleCase { bsdf: "principled_glass", wi: [0.22792116, 0.34188172, -0.91168463], u: 0.9, u2: (0.55, 0.1), wo: [-0.2912743, -0.44757918, 0.8454775], pdf: 16.866817, weight: [1.0762191, 0.9491361, 0.80216634] },
    SampleCase { bsdf: "principled_glass", wi: [0.22792116, 0.34188172, -0.91168463], u: 0.05, u2: (0.8, 0.45), wo: [-0.29812187, -0.50958925, 0.8071197], pdf: 46.851944, weight: [1.0759232, 0.9488751, 0.80194587] },
    SampleCase { bsdf: "principled_glass", wi: [0.22792116, 0.34188172, -0.91168463], u: 0.6, u2: (0.33, 0.91), wo: [-0.38466382, -0.5367112, 0.75098276], pdf: 9.761974, weight: [1.075407, 0.94841987, 0.80156106] },
    SampleCase { bsdf: "conductor_smooth", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.3, u2: (0.2, 0.7), wo: [-0.3487429, -0.11624764, 0.9299811], pdf: 1.0, weight: [0.95185626, 0.61574686, 0.5244242] },
    SampleCase { bsdf: "conductor_smooth", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.9, u2: (0.55, 0.1), wo: [-0.3487429, -0.11624764, 0.9299811], pdf: 1.0, weight: [0.95185626, 0.61574686, 0.5244242] },
    SampleCase { bsdf: "conductor_smooth", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.05, u2: (0.8, 0.45), wo: [-0.3487429, -0.11624764, 0.9299811], pdf: 1.0, weight: [0.95185626, 0.61574686, 0.5244242] },
    SampleCase { bsdf: "conductor_smooth", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.6, u2: (0.33, 0.91), wo: [-0.3487429, -0.11624764, 0.9299811], pdf: 1.0, weight: [0.95185626, 0.61574686, 0.5244242] },
    SampleCase { bsdf: "conductor_smooth", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.3, u2: (0.2, 0.7), wo: [-0.7442084, 0.24806947, 0.6201737], pdf: 1.0, weight: [0.9485914, 0.6175681, 0.53140694] },
    SampleCase { bsdf: "conductor_smooth", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.9, u2: (0.55, 0.1), wo: [-0.7442084, 0.24806947, 0.6201737], pdf: 1.0, weight: [0.9485914, 0.6175681, 0.53140694] },
    SampleCase { bsdf: "conductor_smooth", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.05, u2: (0.8, 0.45), wo: [-0.7442084, 0.24806947, 0.6201737], pdf: 1.0, weight: [0.9485914, 0.6175681, 0.53140694] },
    SampleCase { bsdf: "conductor_smooth", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.6, u2: (0.33, 0.91), wo: [-0.7442084, 0.24806947, 0.6201737], pdf: 1.0, weight: [0.9485914, 0.6175681, 0.53140694] },
    SampleCase { bsdf: "dielectric_smooth", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.3, u2: (0.2, 0.7), wo: [-0.23249528, -0.07749843, -0.969505], pdf: 0.95963424, weight: [0.44444448, 0.44444448, 0.44444448] },
    SampleCase { bsdf: "dielectric_smooth", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.9, u2: (0.55, 0.1), wo: [-0.23249528, -0.07749843, -0.969505], pdf: 0.95963424, weight: [0.44444448, 0.44444448, 0.44444448] },
    SampleCase { bsdf: "dielectric_smooth", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.05, u2: (0.8, 0.45), wo: [-0.23249528, -0.07749843, -0.969505], pdf: 0.95963424, weight: [0.44444448, 0.44444448, 0.44444448] },
    SampleCase { bsdf: "dielectric_smooth", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.6, u2: (0.33, 0.91), wo: [-0.23249528, -0.07749843, -0.969505], pdf: 0.95963424, weight: [0.44444448, 0.44444448, 0.44444448] },
    SampleCase { bsdf: "dielectric_smooth", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.3, u2: (0.2, 0.7), wo: [-0.49613893, 0.16537964, -0.8523472], pdf: 0.93893164, weight: [0.44444448, 0.44444448, 0.44444448] },
    SampleCase { bsdf: "dielectric_smooth", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.9, u2: (0.55, 0.1), wo: [-0.49613893, 0.16537964, -0.8523472], pdf: 0.93893164, weight: [0.44444448, 0.44444448, 0.44444448] },
    SampleCase { bsdf: "dielectric_smooth", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.05, u2: (0.8, 0.45), wo: [-0.7442084, 0.24806947, 0.6201737], pdf: 0.061068352, weight: [1.0, 1.0, 1.0] },
    SampleCase { bsdf: "dielectric_smooth", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.6, u2: (0.33, 0.91), wo: [-0.49613893, 0.16537964, -0.8523472], pdf: 0.93893164, weight: [0.44444448, 0.44444448, 0.44444448] },
    SampleCase { bsdf: "dielectric_smooth", wi: [0.22792116, 0.34188172, -0.91168463], u: 0.3, u2: (0.2, 0.7), wo: [-0.34188175, -0.51282257, 0.7874833], pdf: 0.9554832, weight: [2.25, 2.25, 2.25] },
    SampleCase { bsdf: "dielectric_smooth", wi: [0.22792116, 0.34188172, -0.91168463], u: 0.9, u2: (0.55, 0.1), wo: [-0.34188175, -0.51282257, 0.7874833], pdf: 0.9554832, weight: [2.25, 2.25, 2.25] },
    SampleCase { bsdf: "dielectric_smooth", wi: [0.22792116, 0.34188172, -0.91168463], u: 0.05, u2: (0.8, 0.45), wo: [-0.34188175, -0.51282257, 0.7874833], pdf: 0.9554832, weight: [2.25, 2.25, 2.25] },
    SampleCase { bsdf: "dielectric_smooth", wi: [0.22792116, 0.34188172, -0.91168463], u: 0.6, u2: (0.33, 0.91), wo: [-0.34188175, -0.51282257, 0.7874833], pdf: 0.9554832, weight: [2.25, 2.25, 2.25] },
    SampleCase { bsdf: "thin", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.3, u2: (0.2, 0.7), wo: [-0.3487429, -0.11624764, -0.9299811], pdf: 0.92240083, weight: [1.0, 1.0, 1.0] },
    SampleCase { bsdf: "thin", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.9, u2: (0.55, 0.1), wo: [-0.3487429, -0.11624764, -0.9299811], pdf: 0.92240083, weight: [1.0, 1.0, 1.0] },
    SampleCase { bsdf: "thin", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.05, u2: (0.8, 0.45), wo: [-0.3487429, -0.11624764, 0.9299811], pdf: 0.0775992, weight: [1.0, 1.0, 1.0] },
    SampleCase { bsdf: "thin", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.6, u2: (0.33, 0.91), wo: [-0.3487429, -0.11624764, -0.9299811], pdf: 0.92240083, weight: [1.0, 1.0, 1.0] },
    SampleCase { bsdf: "thin", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.3, u2: (0.2, 0.7), wo: [-0.7442084, 0.24806947, -0.6201737], pdf: 0.8848927, weight: [1.0, 1.0, 1.0] },
    SampleCase { bsdf: "thin", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.9, u2: (0.55, 0.1), wo: [-0.7442084, 0.24806947, -0.6201737], pdf: 0.8848927, weight: [1.0, 1.0, 1.0] },
    SampleCase { bsdf: "thin", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.05, u2: (0.8, 0.45), wo: [-0.7442084, 0.24806947, 0.6201737], pdf: 0.1151073, weight: [1.0, 1.0, 1.0] },
    SampleCase { bsdf: "thin", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.6, u2: (0.33, 0.91), wo: [-0.7442084, 0.24806947, -0.6201737], pdf: 0.8848927, weight: [1.0, 1.0, 1.0] },
    SampleCase { bsdf: "thin", wi: [0.22792116, 0.34188172, -0.91168463], u: 0.3, u2: (0.2, 0.7), wo: [-0.22792116, -0.34188172, 0.91168463], pdf: 0.92196184, weight: [1.0, 1.0, 1.0] },
    SampleCase { bsdf: "thin", wi: [0.22792116, 0.34188172, -0.91168463], u: 0.9, u2: (0.55, 0.1), wo: [-0.22792116, -0.34188172, 0.91168463], pdf: 0.92196184, weight: [1.0, 1.0, 1.0] },
    SampleCase { bsdf: "thin", wi: [0.22792116, 0.34188172, -0.91168463], u: 0.05, u2: (0.8, 0.45), wo: [-0.22792116, -0.34188172, -0.91168463], pdf: 0.078038156, weight: [1.0, 1.0, 1.0] },
    SampleCase { bsdf: "thin", wi: [0.22792116, 0.34188172, -0.91168463], u: 0.6, u2: (0.33, 0.91), wo: [-0.22792116, -0.34188172, 0.91168463], pdf: 0.92196184, weight: [1.0, 1.0, 1.0] },
    SampleCase { bsdf: "thin_glossy", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.3, u2: (0.2, 0.7), wo: [-0.40557906, -0.077162944, -0.91079736], pdf: 4.391783, weight: [1.5466013, 0.9666258, 0.5799755] },
    SampleCase { bsdf: "thin_glossy", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.9, u2: (0.55, 0.1), wo: [-0.07841378, 0.79614776, -0.6], pdf: 0.03083771, weight: [0.80684114, 0.5042757, 0.30256543] },
    SampleCase { bsdf: "thin_glossy", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.05, u2: (0.8, 0.45), wo: [-0.22301395, -0.27281445, 0.9358617], pdf: 0.4728305, weight: [0.16093713, 0.1112739, 0.07816509] },
    SampleCase { bsdf: "thin_glossy", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.6, u2: (0.33, 0.91), wo: [-0.2623405, 0.77690256, 0.5723635], pdf: 0.04641535, weight: [0.707011, 0.44264042, 0.26639342] },
    SampleCase { bsdf: "thin_glossy", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.3, u2: (0.2, 0.7), wo: [-0.7578207, 0.27839598, -0.5900877], pdf: 6.9989033, weight: [1.516403, 0.9477519, 0.5686511] },
    SampleCase { bsdf: "thin_glossy", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.9, u2: (0.55, 0.1), wo: [-0.07841378, 0.79614776, -0.6], pdf: 0.031323172, weight: [0.81820637, 0.511379, 0.30682737] },
    SampleCase { bsdf: "thin_glossy", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.05, u2: (0.8, 0.45), wo: [-0.6855624, 0.115501, 0.7187934], pdf: 0.5562556, weight: [0.15125532, 0.11160276, 0.08516773] },
    SampleCase { bsdf: "thin_glossy", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.6, u2: (0.33, 0.91), wo: [-0.2623405, 0.77690256, 0.5723635], pdf: 0.05173681, weight: [0.7022497, 0.44253716, 0.26939547] },
    SampleCase { bsdf: "thin_glossy", wi: [0.22792116, 0.34188172, -0.91168463], u: 0.3, u2: (0.2, 0.7), wo: [-0.3110149, -0.32346424, 0.893667], pdf: 4.461902, weight: [1.5466056, 0.96662855, 0.57997715] },
    SampleCase { bsdf: "thin_glossy", wi: [0.22792116, 0.34188172, -0.91168463], u: 0.9, u2: (0.55, 0.1), wo: [0.07841378, -0.79614776, 0.6], pdf: 0.032912593, weight: [0.8536305, 0.5335191, 0.32011142] },
    SampleCase { bsdf: "thin_glossy", wi: [0.22792116, 0.34188172, -0.91168463], u: 0.05, u2: (0.8, 0.45), wo: [0.008778921, -0.44318107, -0.89638925], pdf: 0.48854524, weight: [0.1552303, 0.1079458, 0.07642279] },
    SampleCase { bsdf: "thin_glossy", wi: [0.22792116, 0.34188172, -0.91168463], u: 0.6, u2: (0.33, 0.91), wo: [0.2623405, -0.77690256, -0.5723635], pdf: 0.060072966, weight: [0.56416935, 0.35641617, 0.2179141] },
    SampleCase { bsdf: "thin_diffuse", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.3, u2: (0.2, 0.7), wo: [0.5196153, -0.29999998, -0.8], pdf: 0.2006317, weight: [0.24749999, 0.49499997, 0.74249995] },
    SampleCase { bsdf: "thin_diffuse", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.9, u2: (0.55, 0.1), wo: [-0.07841378, 0.79614776, -0.6], pdf: 0.15047377, weight: [0.2475, 0.495, 0.74249995] },
    SampleCase { bsdf: "thin_diffuse", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.05, u2: (0.8, 0.45), wo: [0.59486693, -0.07831574, 0.8], pdf: 0.05401623, weight: [0.4951369, 0.9902738, 1.4854106] },
    SampleCase { bsdf: "thin_diffuse", wi: [0.3487429, 0.11624764, 0.9299811], u: 0.6, u2: (0.33, 0.91), wo: [0.2623405, -0.77690256, -0.5723635], pdf: 0.14354283, weight: [0.24749999, 0.49499997, 0.7424999] },
    SampleCase { bsdf: "thin_diffuse", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.3, u2: (0.2, 0.7), wo: [0.5196153, -0.29999998, -0.8], pdf: 0.2006317, weight: [0.24749999, 0.49499997, 0.74249995] },
    SampleCase { bsdf: "thin_diffuse", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.9, u2: (0.55, 0.1), wo: [-0.07841378, 0.79614776, -0.6], pdf: 0.15047377, weight: [0.2475, 0.495, 0.74249995] },
    SampleCase { bsdf: "thin_diffuse", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.05, u2: (0.8, 0.45), wo: [0.59486693, -0.07831574, 0.8], pdf: 0.05401623, weight: [0.49854648, 0.99709296, 1.4956392] },
    SampleCase { bsdf: "thin_diffuse", wi: [0.7442084, -0.24806947, 0.6201737], u: 0.6, u2: (0.33, 0.91), wo: [0.2623405, -0.77690256, -0.5723635], pdf: 0.14354283, weight: [0.24749999, 0.49499997, 0.7424999] },
    SampleCase { bsdf: "thin_diffuse", wi: [0.22792116, 0.34188172, -0.91168463], u: 0.3, u2: (0.2, 0.7), wo: [-0.5196153, 0.29999998, 0.8], pdf: 0.2006317, weight: [0.24749999, 0.49499997, 0.74249995] },
    SampleCase { bsdf: "thin_diffuse", wi: [0.22792116, 0.34188172, -0.91168463], u: 0.9, u2: (0.55, 0.1), wo: [0.07841378, -0.79614776, 0.6], pdf: 0.15047377, weight: [0.2475, 0.495, 0.74249995] },
    SampleCase { bsdf: "thin_diffuse", wi: [0.22792116, 0.34188172, -0.91168463], u: 0.05, u2: (0.8, 0.45), wo: [-0.59486693, 0.07831574, -0.8], pdf: 0.05401623, weight: [0.49511763, 0.99021983, 1.4853219] },
    SampleCase { bsdf: "thin_diffuse", wi: [0.22792116, 0.34188172, -0.91168463], u: 0.6, u2: (0.33, 0.91), wo: [-0.2623405, 0.77690256, 0.5723635], pdf: 0.14354283, weight: [0.24749999, 0.49499997, 0.7424999] },
];

fn v(a: [f32; 3]) -> Vec3 {
    Vec3::from_array(a)
}

/// |a − b| within `rel` of the larger magnitude, or within `abs` (values near zero).
fn close(a: f32, b: f32, rel: f32, abs: f32) -> bool {
    let d = (a - b).abs();
    d <= abs || d <= rel * a.abs().max(b.abs())
}

#[test]
fn eval_and_pdf_match_mitsuba() {
    // A rough plastic's tables take a while to build: one of each.
    let mut cache = std::collections::HashMap::new();
    let mut bad = Vec::new();
    for c in EVAL_CASES {
        let b = cache.entry(c.bsdf).or_insert_with(|| named(c.bsdf));
        let (wi, wo) = (v(c.wi), v(c.wo));
        let e = b.eval(wi, wo);
        let p = b.pdf(wi, wo);
        let ok = (0..3).all(|i| close(e[i], c.eval[i], 1e-3, 1e-6)) && close(p, c.pdf, 1e-3, 1e-6);
        if !ok {
            bad.push(format!(
                "{} wi {:?} wo {:?}: eval {e} pdf {p}, Mitsuba {:?} {}",
                c.bsdf, c.wi, c.wo, c.eval, c.pdf
            ));
        }
    }
    assert!(
        bad.is_empty(),
        "{} of {} differ:\n{}",
        bad.len(),
        EVAL_CASES.len(),
        bad.join("\n")
    );
}

#[test]
fn samples_match_mitsuba() {
    let mut cache = std::collections::HashMap::new();
    let mut bad = Vec::new();
    for c in SAMPLE_CASES {
        let b = cache.entry(c.bsdf).or_insert_with(|| named(c.bsdf));
        let Some(s) = b.sample(v(c.wi), c.u, c.u2) else {
            bad.push(format!(
                "{} wi {:?} u {} {:?}: no sample",
                c.bsdf, c.wi, c.u, c.u2
            ));
            continue;
        };
        // Mitsuba's weight for plain-normal sampling of rough dielectrics omits the
        // widening of the roughness it samples with; ours is eval/pdf (checked below).
        let check_weight = !c.bsdf.starts_with("dielectric") || !c.bsdf.ends_with("plain");
        let ok = (0..3).all(|i| close(s.wo[i], c.wo[i], 1e-3, 1e-4))
            && close(s.pdf, c.pdf, 2e-3, 1e-6)
            && (!check_weight || (0..3).all(|i| close(s.weight[i], c.weight[i], 2e-3, 1e-6)));
        if !ok {
            bad.push(format!(
                "{} wi {:?} u {} {:?}: wo {} pdf {} weight {}, Mitsuba {:?} {} {:?}",
                c.bsdf, c.wi, c.u, c.u2, s.wo, s.pdf, s.weight, c.wo, c.pdf, c.weight
            ));
        }
    }
    assert!(
        bad.is_empty(),
        "{} of {} differ:\n{}",
        bad.len(),
        SAMPLE_CASES.len(),
        bad.join("\n")
    );
}

/// A unit direction at polar angle `theta_deg` from +z (negative: from −z, the back
/// side), azimuth `phi`.
fn dir(theta_deg: f32, phi: f32) -> Vec3 {
    let t = theta_deg.to_radians();
    vec3(t.sin() * phi.cos(), t.sin() * phi.sin(), t.cos())
}

/// The incident directions the statistical tests use: near normal, oblique, grazing.
const THETAS: [f32; 4] = [5.0, 35.0, 65.0, 85.0];

/// ∫ eval dω over the whole sphere in importance transport (the dielectrics' radiance
/// scaling divided out), by jittered strata: each side of the surface in polar
/// coordinates about the direction its lobe peaks at (the mirror direction on wi's side,
/// the refracted one beyond), θ' = π t² for t stratified, so that strata are finest where
/// narrow lobes are (a refracted lobe of α = 0.1 into water is 0.03 rad wide).
fn albedo_by_eval(b: &Bsdf, wi: Vec3, rng: &mut Rng) -> Vec3 {
    let (nt, nphi) = (192, 384);
    let up = wi.z.signum();
    let mut sides = vec![(vec3(-wi.x, -wi.y, wi.z), up)];
    if b.has_transmission() {
        let eta = match b {
            Bsdf::Dielectric { eta, .. } => *eta,
            Bsdf::Principled(p) => p.relative_eta(),
            _ => 1.0,
        };
        let (_, cos_t, _, eta_ti) = fresnel_dielectric(wi.z, eta);
        let axis = if cos_t != 0.0 {
            vec3(-eta_ti * wi.x, -eta_ti * wi.y, cos_t).normalize()
        } else {
            vec3(0.0, 0.0, -up)
        };
        sides.push((axis, -up));
    }
    let mut sum = Vec3::ZERO;
    for (axis, side) in sides {
        let (tx, ty) = axis.any_orthonormal_pair();
        for i in 0..nt {
            for j in 0..nphi {
                let t = (i as f32 + rng.next_f32()) / nt as f32;
                let theta = std::f32::consts::PI * t * t;
                let phi = std::f32::consts::TAU * (j as f32 + rng.next_f32()) / nphi as f32;
                let wo = axis * theta.cos() + (tx * phi.cos() + ty * phi.sin()) * theta.sin();
                if wo.z * side <= 0.0 {
                    continue;
                }
                // dω = sin θ' dθ' dφ, dθ' = 2π t dt.
                let jacobian = theta.sin() * 2.0 * std::f32::consts::PI * t;
                sum += b.eval(wi, wo) / b.radiance_scale(wi, wo) * jacobian;
            }
        }
    }
    sum * (std::f32::consts::TAU / (nt * nphi) as f32)
}

/// The mean of `sample`'s weights in importance transport (missing draws count 0): all
/// of them, and those of the non-delta lobes alone (the part `eval` integrates).
fn albedo_by_sampling(b: &Bsdf, wi: Vec3, n: usize, rng: &mut Rng) -> (Vec3, Vec3) {
    let (mut all, mut smooth) = (Vec3::ZERO, Vec3::ZERO);
    for _ in 0..n {
        let u = rng.next_f32();
        let u2 = (rng.next_f32(), rng.next_f32());
        if let Some(s) = b.sample(wi, u, u2) {
            let w = s.weight / b.radiance_scale(wi, s.wo);
            all += w;
            if !s.delta {
                smooth += w;
            }
        }
    }
    (all / n as f32, smooth / n as f32)
}

/// The furnace's cases: a BSDF, whether it is lossless (then the albedo must be 1 within
/// 1% for incidence up to `lossless_up_to` degrees, on each side it takes light from),
/// and whether it takes light from the back.
struct Furnace {
    name: &'static str,
    bsdf: Bsdf,
    lossless_up_to: Option<f32>,
    two_sided: bool,
}

fn white_conductor(d: Option<Microfacet>) -> Bsdf {
    // η = 0, k = 1: Fresnel 1 at every angle (Mitsuba's `material = "none"`).
    Bsdf::Conductor {
        eta: Vec3::ZERO,
        k: Vec3::ONE,
        specular: Vec3::ONE,
        distribution: d,
    }
}

fn white_dielectric(eta: f32, d: Option<Microfacet>) -> Bsdf {
    Bsdf::Dielectric {
        eta,
        reflectance: Vec3::ONE,
        transmittance: Vec3::ONE,
        distribution: d,
    }
}

fn furnaces() -> Vec<Furnace> {
    let f = |name, bsdf, lossless_up_to, two_sided| Furnace {
        name,
        bsdf,
        lossless_up_to,
        two_sided,
    };
    vec![
        f(
            "diffuse",
            Bsdf::Diffuse {
                reflectance: Vec3::ONE,
            },
            Some(90.0),
            false,
        ),
        f("conductor smooth", white_conductor(None), Some(90.0), false),
        f(
            "conductor GGX 0.05",
            white_conductor(mf(Ggx, 0.05, 0.05, true)),
            Some(35.0),
            false,
        ),
        f(
            "conductor Beckmann 0.05 plain",
            white_conductor(mf(Beckmann, 0.05, 0.05, false)),
            Some(65.0),
            false,
        ),
        f(
            "conductor GGX 0.5",
            white_conductor(mf(Ggx, 0.5, 0.5, true)),
            None,
            false,
        ),
        f(
            "conductor Beckmann 0.1x0.4",
            white_conductor(mf(Beckmann, 0.1, 0.4, true)),
            None,
            false,
        ),
        f(
            "conductor copper GGX 0.3",
            named("conductor_ggx"),
            None,
            false,
        ),
        f(
            "dielectric smooth",
            white_dielectric(1.5, None),
            Some(90.0),
            true,
        ),
        f(
            "dielectric GGX 0.05",
            white_dielectric(1.5, mf(Ggx, 0.05, 0.05, true)),
            Some(35.0),
            true,
        ),
        f(
            "dielectric Beckmann 0.1 plain",
            white_dielectric(1.33, mf(Beckmann, 0.1, 0.1, false)),
            Some(65.0),
            true,
        ),
        f(
            "dielectric GGX 0.5",
            white_dielectric(1.5, mf(Ggx, 0.5, 0.5, true)),
            None,
            true,
        ),
        f(
            "dielectric tinted",
            named("dielectric_beckmann_plain"),
            None,
            true,
        ),
        f(
            "thin dielectric",
            Bsdf::ThinDielectric {
                eta: 1.5,
                reflectance: Vec3::ONE,
                transmittance: Vec3::ONE,
            },
            Some(90.0),
            true,
        ),
        f(
            "plastic white",
            Bsdf::Plastic(Plastic::new(Vec3::ONE, Vec3::ONE, 1.49, false, None)),
            Some(90.0),
            false,
        ),
        f(
            "plastic nonlinear",
            named("plastic_smooth_nonlinear"),
            None,
            false,
        ),
        f(
            "roughplastic white GGX 0.2",
            Bsdf::Plastic(Plastic::new(
                Vec3::ONE,
                Vec3::ONE,
                1.49,
                false,
                mf(Ggx, 0.2, 0.2, true),
            )),
            None,
            false,
        ),
        f(
            "roughplastic Beckmann 0.3 nonlinear",
            named("plastic_rough_beckmann_nonlinear"),
            None,
            false,
        ),
        f("principled opaque", named("principled_opaque"), None, false),
        f("principled glass", named("principled_glass"), None, true),
        f("principledthin glossy", named("thin_glossy"), None, true),
        f("principledthin diffuse", named("thin_diffuse"), None, true),
        // White, smooth-diffuse and fully transmitting or reflecting, it loses nothing.
        f(
            "principledthin white diffuse transmitter",
            Bsdf::PrincipledThin(PrincipledThin {
                base_color: Vec3::ONE,
                roughness: 0.0,
                diff_trans: 2.0,
                ..PrincipledThin::default()
            }),
            Some(90.0),
            true,
        ),
    ]
}

#[test]
fn white_furnace() {
    let mut rng = Rng::new(7, 1, 2);
    let mut bad = Vec::new();
    let mut report = Vec::new();
    for c in furnaces() {
        let sides: &[f32] = if c.two_sided { &[1.0, -1.0] } else { &[1.0] };
        for &side in sides {
            for &t in &THETAS {
                let mut wi = dir(t, 0.7);
                wi.z *= side;
                let by_eval = if c.bsdf.is_delta() {
                    None
                } else {
                    Some(albedo_by_eval(&c.bsdf, wi, &mut rng))
                };
                let (by_sampling, non_delta) = albedo_by_sampling(&c.bsdf, wi, 60_000, &mut rng);
                let lossless = c.lossless_up_to.is_some_and(|m| t <= m);
                // With a delta lobe (smooth plastic's coat) ∫eval is only the rest.
                let has_delta_lobe = (by_sampling - non_delta).max_element() > 0.0;
                let mut check = |what: &str, a: Vec3, lossless: bool| {
                    report.push(format!(
                        "{} θ {}{t}° {what}: {a}",
                        c.name,
                        if side < 0.0 { "−" } else { "" }
                    ));
                    if a.max_element() > 1.01 || (lossless && a.min_element() < 0.99) {
                        bad.push(format!("{} wi θ {t}° side {side}: {what} {a}", c.name));
                    }
                };
                if let Some(e) = by_eval {
                    check("∫eval", e, lossless && !has_delta_lobe);
                }
                check("mean weight", by_sampling, lossless);
                if let Some(e) = by_eval {
                    // The two estimates of one integral agree (within their noise).
                    if (e - non_delta).abs().max_element() > 0.02 * e.max_element().max(0.05) {
                        bad.push(format!(
                            "{} θ {t}° side {side}: ∫eval {e} ≠ mean weight {non_delta} \
                             of the non-delta lobes",
                            c.name
                        ));
                    }
                }
            }
        }
    }
    println!("{}", report.join("\n"));
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

#[test]
fn weight_is_eval_over_pdf() {
    let mut rng = Rng::new(11, 3, 4);
    let names = [
        "conductor_ggx",
        "conductor_beckmann_aniso_plain",
        "conductor_ggx_aniso",
        "dielectric_ggx",
        "dielectric_beckmann_plain",
        "plastic_rough_ggx",
        "plastic_rough_beckmann_nonlinear",
        "plastic_smooth",
        "plastic_smooth_nonlinear",
        "diffuse",
        "principled_opaque",
        "principled_glass",
        "thin_glossy",
        "thin_diffuse",
    ];
    let mut bad = Vec::new();
    let mut checked = 0;
    for name in names {
        let b = named(name);
        for side in [1.0, -1.0] {
            for &t in &THETAS {
                let mut wi = dir(t, 2.1);
                wi.z *= side;
                for _ in 0..2000 {
                    let u = rng.next_f32();
                    let u2 = (rng.next_f32(), rng.next_f32());
                    let Some(s) = b.sample(wi, u, u2) else {
                        continue;
                    };
                    if s.delta {
                        continue;
                    }
                    checked += 1;
                    let e = b.eval(wi, s.wo);
                    let p = b.pdf(wi, s.wo);
                    let expect = e / p;
                    let ok = close(s.pdf, p, 2e-3, 1e-7)
                        && (0..3).all(|i| close(s.weight[i], expect[i], 2e-3, 1e-6));
                    if !ok {
                        bad.push(format!(
                            "{name} wi {wi} wo {}: weight {} pdf {}, eval/pdf {expect} pdf {p}",
                            s.wo, s.weight, s.pdf
                        ));
                    }
                }
            }
        }
    }
    assert!(checked > 50_000, "only {checked} samples");
    assert!(
        bad.is_empty(),
        "{} of {checked}:\n{}",
        bad.len(),
        bad[..bad.len().min(20)].join("\n")
    );
}

#[test]
fn delta_bsdfs_have_no_density() {
    let mut rng = Rng::new(5, 6, 7);
    for name in ["conductor_smooth", "dielectric_smooth", "thin"] {
        let b = named(name);
        assert!(b.is_delta(), "{name}");
        for _ in 0..200 {
            let wi = dir(80.0 * rng.next_f32(), 6.0 * rng.next_f32());
            let s = b
                .sample(wi, rng.next_f32(), (0.5, 0.5))
                .expect("a delta sample");
            assert!(s.delta, "{name}");
            assert_eq!(b.eval(wi, s.wo), Vec3::ZERO, "{name}");
            assert_eq!(b.pdf(wi, s.wo), 0.0, "{name}");
        }
    }
    // Smooth plastic: its coat is delta, its base not.
    let p = named("plastic_smooth");
    assert!(!p.is_delta());
    let deltas = (0..1000)
        .filter_map(|i| p.sample(dir(30.0, 1.0), i as f32 / 1000.0, (0.3, 0.6)))
        .filter(|s: &BsdfSample| s.delta)
        .count();
    assert!(deltas > 0 && deltas < 1000, "{deltas}");
}

/// The upper regularized incomplete gamma function Q(a, x), by its series below a + 1 and
/// Lentz's continued fraction above (Numerical Recipes' split).
fn gamma_q(a: f64, x: f64) -> f64 {
    fn ln_gamma(z: f64) -> f64 {
        // Lanczos (g = 7, n = 9).
        let c = [
            0.999_999_999_999_809_9,
            676.520_368_121_885_1,
            -1_259.139_216_722_402_8,
            771.323_428_777_653_1,
            -176.615_029_162_140_6,
            12.507_343_278_686_905,
            -0.138_571_095_265_720_12,
            9.984_369_578_019_572e-6,
            1.505_632_735_149_311_6e-7,
        ];
        let z = z - 1.0;
        let mut s = c[0];
        for (i, &ci) in c.iter().enumerate().skip(1) {
            s += ci / (z + i as f64);
        }
        let t = z + 7.5;
        0.5 * (2.0 * std::f64::consts::PI).ln() + (z + 0.5) * t.ln() - t + s.ln()
    }
    if x <= 0.0 {
        return 1.0;
    }
    let lg = ln_gamma(a);
    if x < a + 1.0 {
        let (mut sum, mut term, mut ap) = (1.0 / a, 1.0 / a, a);
        for _ in 0..10_000 {
            ap += 1.0;
            term *= x / ap;
            sum += term;
            if term.abs() < sum.abs() * 1e-15 {
                break;
            }
        }
        1.0 - sum * (-x + a * x.ln() - lg).exp()
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < 1e-15 {
                break;
            }
        }
        (-x + a * x.ln() - lg).exp() * h
    }
}

/// The bins of the χ² test: θ ∈ [0, π] and φ ∈ [0, 2π) on a regular grid.
const RES_THETA: usize = 24;
const RES_PHI: usize = 48;

fn bin_of(w: Vec3) -> usize {
    let theta = w.z.clamp(-1.0, 1.0).acos();
    let mut phi = w.y.atan2(w.x);
    if phi < 0.0 {
        phi += std::f32::consts::TAU;
    }
    let i = ((theta / std::f32::consts::PI * RES_THETA as f32) as usize).min(RES_THETA - 1);
    let j = ((phi / std::f32::consts::TAU * RES_PHI as f32) as usize).min(RES_PHI - 1);
    i * RES_PHI + j
}

/// The expected fraction of draws in each bin: `pdf` integrated over the bin by 3×3
/// sub-cells of a 2D Gauss–Legendre rule of 6² points each (in θ and φ, with the sin θ of
/// solid angle): fine enough for the edges of a refracted lobe's support.
fn expected_fractions(b: &Bsdf, wi: Vec3) -> Vec<f64> {
    // 6-point Gauss–Legendre nodes and weights on [−1, 1].
    let gl = [
        (-0.932_469_514_203_152, 0.171_324_492_379_170),
        (-0.661_209_386_466_265, 0.360_761_573_048_139),
        (-0.238_619_186_083_197, 0.467_913_934_572_691),
        (0.238_619_186_083_197, 0.467_913_934_572_691),
        (0.661_209_386_466_265, 0.360_761_573_048_139),
        (0.932_469_514_203_152, 0.171_324_492_379_170),
    ];
    const SUB: usize = 3;
    let dt = std::f64::consts::PI / (RES_THETA * SUB) as f64;
    let dp = std::f64::consts::TAU / (RES_PHI * SUB) as f64;
    let mut out = vec![0.0; RES_THETA * RES_PHI];
    for i in 0..RES_THETA * SUB {
        for j in 0..RES_PHI * SUB {
            let mut s = 0.0;
            for &(x, wx) in &gl {
                let theta = (i as f64 + 0.5 + 0.5 * x) * dt;
                for &(y, wy) in &gl {
                    let phi = (j as f64 + 0.5 + 0.5 * y) * dp;
                    let w = vec3(
                        (theta.sin() * phi.cos()) as f32,
                        (theta.sin() * phi.sin()) as f32,
                        theta.cos() as f32,
                    );
                    s += wx * wy * f64::from(b.pdf(wi, w)) * theta.sin();
                }
            }
            out[(i / SUB) * RES_PHI + j / SUB] += s * 0.25 * dt * dp;
        }
    }
    out
}

/// Pearson's χ² test of `sample`'s non-delta directions from `wi` against `pdf`, over
/// `n` draws: the p-value of the directions' distribution (the draws that gave one,
/// against `pdf` normalized to them; cells of expected count below 5 pooled), and the
/// fraction of draws that gave one minus ∫ pdf, which must be 0 within the noise and the
/// error of Beckmann's rational Smith G1 (Mitsuba's fit, below 0.35%: its visible-normal
/// density integrates to 1 within that). A direction drawn where `pdf` is 0 fails
/// outright (p = 0).
fn chi2_test(b: &Bsdf, wi: Vec3, n: usize, rng: &mut Rng) -> (f64, f64, String) {
    let mut observed = vec![0u64; RES_THETA * RES_PHI];
    for _ in 0..n {
        let u = rng.next_f32();
        let u2 = (rng.next_f32(), rng.next_f32());
        if let Some(s) = b.sample(wi, u, u2).filter(|s| !s.delta) {
            if b.pdf(wi, s.wo).is_nan() || b.pdf(wi, s.wo) <= 0.0 {
                return (0.0, 0.0, format!("drew {} where pdf is 0", s.wo));
            }
            observed[bin_of(s.wo)] += 1
        }
    }
    let fractions = expected_fractions(b, wi);
    let mass: f64 = fractions.iter().sum();
    let drawn = observed.iter().sum::<u64>() as f64;
    let mut cells: Vec<(f64, f64)> = Vec::new();
    let (mut pool_o, mut pool_e) = (0.0, 0.0);
    for (k, f) in fractions.iter().enumerate() {
        let (o, e) = (observed[k] as f64, f / mass * drawn);
        if e < 5.0 {
            pool_o += o;
            pool_e += e;
        } else {
            cells.push((o, e));
        }
    }
    if pool_e >= 5.0 {
        cells.push((pool_o, pool_e));
    } else if let Some(smallest) = cells
        .iter_mut()
        .min_by(|a, b| a.1.partial_cmp(&b.1).unwrap())
    {
        smallest.0 += pool_o;
        smallest.1 += pool_e;
    }
    let chi2: f64 = cells.iter().map(|(o, e)| (o - e) * (o - e) / e).sum();
    let dof = cells.len() - 1;
    let p = gamma_q(dof as f64 / 2.0, chi2 / 2.0);
    let drawn_fraction = drawn / n as f64;
    (
        p,
        drawn_fraction - mass,
        format!(
            "χ² {chi2:.1}, {dof} degrees of freedom; drawn {drawn_fraction:.4}, ∫pdf {mass:.4}"
        ),
    )
}

#[test]
fn gamma_q_matches_known_values() {
    // Q(k/2, x/2) is the χ² survival function: 1 − CDF at x for k degrees of freedom.
    assert!((gamma_q(0.5, 3.841_458_8 / 2.0) - 0.05).abs() < 1e-6);
    assert!((gamma_q(5.0, 23.209_251 / 2.0) - 0.01).abs() < 1e-6);
    assert!((gamma_q(50.0, 149.449_33 / 2.0) - 0.001).abs() < 1e-6);
}

#[test]
fn sampling_matches_pdf_chi2() {
    let dist = |k, au, av, vis| mf(k, au, av, vis);
    let cases: Vec<(&str, Bsdf)> = vec![
        (
            "conductor GGX 0.3 visible",
            white_conductor(dist(Ggx, 0.3, 0.3, true)),
        ),
        (
            "conductor GGX 0.3 plain",
            white_conductor(dist(Ggx, 0.3, 0.3, false)),
        ),
        (
            "conductor Beckmann 0.3 visible",
            white_conductor(dist(Beckmann, 0.3, 0.3, true)),
        ),
        (
            "conductor Beckmann 0.3 plain",
            white_conductor(dist(Beckmann, 0.3, 0.3, false)),
        ),
        (
            "conductor GGX 0.15x0.5 visible",
            white_conductor(dist(Ggx, 0.15, 0.5, true)),
        ),
        (
            "conductor Beckmann 0.5x0.2 plain",
            white_conductor(dist(Beckmann, 0.5, 0.2, false)),
        ),
        (
            "roughdielectric GGX 0.3 visible",
            white_dielectric(1.5, dist(Ggx, 0.3, 0.3, true)),
        ),
        (
            "roughdielectric Beckmann 0.3 plain",
            white_dielectric(1.33, dist(Beckmann, 0.3, 0.3, false)),
        ),
        (
            "roughdielectric GGX 0.5 plain",
            white_dielectric(1.5, dist(Ggx, 0.5, 0.5, false)),
        ),
        (
            "roughdielectric Beckmann 0.2x0.4 visible",
            white_dielectric(1.5, dist(Beckmann, 0.2, 0.4, true)),
        ),
        ("roughplastic GGX 0.2", named("plastic_rough_ggx")),
        (
            "roughplastic Beckmann 0.3 nonlinear",
            named("plastic_rough_beckmann_nonlinear"),
        ),
        ("plastic", named("plastic_smooth")),
        ("diffuse", named("diffuse")),
        ("principled opaque", named("principled_opaque")),
        ("principled glass", named("principled_glass")),
        ("principledthin glossy", named("thin_glossy")),
        ("principledthin diffuse", named("thin_diffuse")),
        (
            "principledthin glass-like",
            Bsdf::PrincipledThin(PrincipledThin {
                roughness: 0.3,
                spec_trans: 0.9,
                eta: 1.6,
                anisotropic: 0.7,
                ..PrincipledThin::default()
            }),
        ),
    ];
    let thetas: [f32; 3] = [10.0, 50.0, 80.0];
    let mut runs = Vec::new();
    for (name, b) in &cases {
        let two_sided = b.has_transmission();
        for &t in &thetas {
            runs.push((*name, b, dir(t, 0.4)));
            if two_sided {
                let w = dir(t, 0.4);
                runs.push((*name, b, vec3(w.x, w.y, -w.z)));
            }
        }
    }
    // Šidák: each of the m tests at 1 − (1 − α)^(1/m), so that one false alarm among all
    // of them has probability α = 1e-3.
    let alpha = 1e-3f64;
    let per_test = 1.0 - (1.0 - alpha).powf(1.0 / runs.len() as f64);
    let mut rng = Rng::new(3, 1, 4);
    let mut bad = Vec::new();
    for (name, b, wi) in runs {
        let (p, missing, what) = chi2_test(b, wi, 200_000, &mut rng);
        println!("{name} wi {wi}: p = {p:.3e} ({what})");
        if p < per_test || missing.abs() > 0.005 {
            bad.push(format!(
                "{name} wi {wi}: p = {p:.3e} < {per_test:.2e} ({what})"
            ));
        }
    }
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

#[test]
fn one_sided_bsdfs_are_black_from_behind() {
    let names = [
        "diffuse",
        "conductor_ggx",
        "conductor_smooth",
        "plastic_smooth",
        "plastic_rough_ggx",
        "principled_opaque",
    ];
    let mut rng = Rng::new(9, 9, 9);
    for name in names {
        let b = named(name);
        assert!(!b.has_transmission(), "{name}");
        for _ in 0..200 {
            let front = dir(85.0 * rng.next_f32(), 6.0 * rng.next_f32());
            let back = vec3(front.x, front.y, -front.z);
            let other = dir(85.0 * rng.next_f32(), 6.0 * rng.next_f32());
            assert!(
                b.sample(back, rng.next_f32(), (0.3, 0.7)).is_none(),
                "{name}"
            );
            assert_eq!(b.eval(back, other), Vec3::ZERO, "{name}");
            assert_eq!(b.eval(other, back), Vec3::ZERO, "{name}");
            assert_eq!(b.pdf(back, other), 0.0, "{name}");
            assert_eq!(b.pdf(other, back), 0.0, "{name}");
        }
    }
}

#[test]
fn diffuse_parts_and_flags() {
    assert_eq!(named("diffuse").diffuse_part(), vec3(0.3, 0.6, 0.9));
    assert_eq!(named("plastic_smooth").diffuse_part(), vec3(0.2, 0.5, 0.7));
    assert_eq!(
        named("principled_glass").diffuse_part(),
        vec3(0.9, 0.7, 0.5)
    );
    assert_eq!(named("conductor_ggx").diffuse_part(), Vec3::ZERO);
    assert_eq!(named("dielectric_ggx").diffuse_part(), Vec3::ZERO);
    assert!(named("principled_glass").has_transmission());
    assert!(!named("dielectric_ggx").is_delta());
    // Radiance leaving glass of η = 1.5 for the air is divided by η² (its solid angle
    // widens), radiance entering it multiplied by η².
    let d = named("dielectric_smooth");
    let (down, up) = (vec3(0.0, 0.0, -1.0), vec3(0.0, 0.0, 1.0));
    assert!((d.radiance_scale(up, down) - 1.0 / 2.25).abs() < 1e-6);
    assert!((d.radiance_scale(down, up) - 2.25).abs() < 1e-5);
    assert_eq!(d.radiance_scale(up, up), 1.0);
}

#[test]
fn values_are_finite_and_non_negative_at_degenerate_directions() {
    let names = [
        "diffuse",
        "conductor_ggx",
        "conductor_beckmann_aniso_plain",
        "conductor_smooth",
        "dielectric_ggx",
        "dielectric_beckmann_plain",
        "dielectric_smooth",
        "thin",
        "plastic_smooth",
        "plastic_rough_ggx",
        "principled_opaque",
        "principled_glass",
        "thin_glossy",
        "thin_diffuse",
    ];
    let z = vec3(0.0, 0.0, 1.0);
    let grazing = vec3(1.0, 0.0, 0.0);
    let a = dir(40.0, 1.0);
    let dirs = [
        z,
        -z,
        grazing,
        -grazing,
        a,
        -a,
        vec3(-a.x, -a.y, a.z),
        vec3(a.x, a.y, -a.z),
        dir(89.99, 0.3),
        dir(0.001, 0.3),
    ];
    let mut rng = Rng::new(2, 7, 1);
    for name in names {
        let b = named(name);
        for &wi in &dirs {
            for &wo in &dirs {
                let (e, p) = (b.eval(wi, wo), b.pdf(wi, wo));
                assert!(
                    e.is_finite() && e.min_element() >= 0.0,
                    "{name} {wi} {wo}: {e}"
                );
                assert!(p.is_finite() && p >= 0.0, "{name} {wi} {wo}: {p}");
            }
            for _ in 0..500 {
                let u2 = (rng.next_f32(), rng.next_f32());
                if let Some(s) = b.sample(wi, rng.next_f32(), u2) {
                    assert!(
                        s.weight.is_finite() && s.weight.min_element() >= 0.0,
                        "{name} {wi}: {s:?}"
                    );
                    assert!(s.pdf.is_finite() && s.pdf > 0.0, "{name} {wi}: {s:?}");
                    assert!((s.wo.length() - 1.0).abs() < 1e-4, "{name} {wi}: {s:?}");
                }
            }
        }
    }
}
