//! Colours as Mitsuba 3's RGB variants make them: spectra given as wavelength–value pairs
//! integrated against the CIE 1931 colour-matching functions into linear sRGB (reflectances
//! under D65, emission as it is), and the named indices of refraction of its dielectrics and
//! conductors.

use super::cie::{CIE_1931_D65, CIE_MAX, CIE_MIN, CIE_Y_NORMALIZATION};
use crate::color::Color;
use crate::geometry::vec3;

/// A spectrum as a scene gives it.
#[derive(Clone, Debug, PartialEq)]
pub enum Spectrum {
    /// The same value at every wavelength.
    Uniform(f64),
    /// Wavelength (nm), value pairs, wavelengths increasing; zero outside their range.
    Pairs(Vec<(f64, f64)>),
}

/// What a spectrum describes, which decides how it becomes RGB.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpectrumUse {
    /// A reflectance or transmittance: seen under D65, clamped to [0, 1].
    Bounded,
    /// An index of refraction or another unbounded quantity: under D65, clamped at 0.
    Unbounded,
    /// Emitted radiance: integrated as it is (no illuminant), clamped at 0.
    Emission,
}

/// Linear sRGB of a spectrum, as Mitsuba's RGB variants compute it.
pub fn spectrum_to_rgb(spectrum: &Spectrum, usage: SpectrumUse) -> Color {
    match spectrum {
        // A uniform emission spectrum is not white in sRGB (its white point is D65): Mitsuba
        // gives it the colour of XYZ (1, 1, 1), so that RGB renders match spectral ones.
        Spectrum::Uniform(v) if usage == SpectrumUse::Emission => xyz_to_srgb([1.0; 3]) * *v as f32,
        Spectrum::Uniform(v) => Color::splat(*v as f32),
        Spectrum::Pairs(pairs) => pairs_to_rgb(pairs, usage),
    }
}

/// The integral of the piecewise-linear spectrum against the colour-matching functions by
/// 1,000 evenly spaced points over the tables' range (the same sum Mitsuba takes, so that
/// the same scene gives the same colours), then to linear sRGB.
fn pairs_to_rgb(pairs: &[(f64, f64)], usage: SpectrumUse) -> Color {
    const STEPS: usize = 1000;
    let (first, last) = (pairs[0].0, pairs[pairs.len() - 1].0);
    let mut xyz = [0.0f64; 3];
    for i in 0..STEPS {
        let w = CIE_MIN + (i as f64 / (STEPS - 1) as f64) * (CIE_MAX - CIE_MIN);
        if w < first || w > last {
            continue;
        }
        let k = pairs
            .partition_point(|p| p.0 <= w)
            .clamp(1, pairs.len().max(2) - 1);
        let value = if pairs.len() == 1 {
            pairs[0].1
        } else {
            let ((w0, v0), (w1, v1)) = (pairs[k - 1], pairs[k]);
            ((w - w1) * v0 + (w0 - w) * v1) / (w0 - w1)
        };
        let [x, y, z, d65] = cie_at(w);
        let weight = value
            * if usage == SpectrumUse::Emission {
                1.0
            } else {
                d65
            };
        xyz[0] += x * weight;
        xyz[1] += y * weight;
        xyz[2] += z * weight;
    }
    let scale = (CIE_MAX - CIE_MIN) * CIE_Y_NORMALIZATION / STEPS as f64;
    let rgb = xyz_to_srgb(xyz.map(|c| c * scale));
    match usage {
        SpectrumUse::Bounded => rgb.clamp(Color::ZERO, Color::ONE),
        SpectrumUse::Unbounded | SpectrumUse::Emission => rgb.max(Color::ZERO),
    }
}

/// The tables at wavelength `w` (nm), linearly interpolated.
fn cie_at(w: f64) -> [f64; 4] {
    let x = ((w - CIE_MIN) / 5.0).clamp(0.0, (CIE_1931_D65.len() - 1) as f64);
    let i = (x as usize).min(CIE_1931_D65.len() - 2);
    let f = x - i as f64;
    let (a, b) = (CIE_1931_D65[i], CIE_1931_D65[i + 1]);
    [0, 1, 2, 3].map(|c| a[c] * (1.0 - f) + b[c] * f)
}

/// CIE XYZ to linear sRGB (D65 white).
pub fn xyz_to_srgb(xyz: [f64; 3]) -> Color {
    const M: [[f64; 3]; 3] = [
        [3.240479, -1.537150, -0.498535],
        [-0.969256, 1.875991, 0.041556],
        [0.055648, -0.204043, 1.057311],
    ];
    let row = |r: [f64; 3]| (r[0] * xyz[0] + r[1] * xyz[1] + r[2] * xyz[2]) as f32;
    vec3(row(M[0]), row(M[1]), row(M[2]))
}

/// The index of refraction of a named dielectric (Mitsuba's `int_ior`/`ext_ior` names).
pub fn named_ior(name: &str) -> Option<f32> {
    DIELECTRICS
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, ior)| *ior)
}

/// The names `named_ior` knows, for error messages.
pub fn ior_names() -> String {
    DIELECTRICS.map(|(n, _)| n).join(", ")
}

/// Measured indices of refraction at 589 nm (sodium D line), as Mitsuba names them.
const DIELECTRICS: [(&str, f32); 23] = [
    ("vacuum", 1.0),
    ("helium", 1.00004),
    ("hydrogen", 1.00013),
    ("air", 1.00028),
    ("carbon dioxide", 1.00045),
    ("water", 1.333),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.47),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.575),
    ("diamond", 2.419),
];

/// The complex index of refraction (η, k) of a named conductor as linear RGB, or None for an
/// unknown name. `none` is Mitsuba's perfect mirror, which `Some` does not describe: the
/// caller handles it.
pub fn named_conductor(name: &str) -> Option<(Color, Color)> {
    CONDUCTORS
        .iter()
        .find(|(n, _, _)| *n == name)
        .map(|(_, eta, k)| (Color::from_array(*eta), Color::from_array(*k)))
}

/// The names `named_conductor` knows, for error messages.
pub fn conductor_names() -> String {
    CONDUCTORS.map(|(n, _, _)| n).join(", ")
}

/// Measured complex indices of refraction of metals and semiconductors, integrated to linear
/// RGB as Mitsuba's RGB variants integrate their spectra (no illuminant, clamped at 0).
const CONDUCTORS: [(&str, [f32; 3], [f32; 3]); 65] = [
    (
        "a-C",
        [2.94405, 2.22714, 1.96816],
        [0.887465, 0.799299, 0.81529],
    ),
    (
        "Ag",
        [0.155276, 0.116728, 0.138388],
        [4.82835, 3.12222, 2.1469],
    ),
    ("Al", [1.6575, 0.880405, 0.521244], [9.22381, 6.2695, 4.837]),
    (
        "AlAs",
        [3.6053, 3.23294, 2.21632],
        [0.000679437, 0.0, 0.00751271],
    ),
    (
        "AlAs_palik",
        [3.6053, 3.23294, 2.21632],
        [0.000679437, 0.0, 0.00751271],
    ),
    ("AlSb", [0.0, 4.13937, 4.66925], [0.0, 0.0940091, 1.30057]),
    (
        "AlSb_palik",
        [0.0, 4.13937, 4.66925],
        [0.0, 0.0940091, 1.30057],
    ),
    (
        "Au",
        [0.143036, 0.375307, 1.44205],
        [3.983, 2.38556, 1.60336],
    ),
    (
        "Be",
        [4.18501, 3.18503, 2.78406],
        [3.83547, 3.01012, 2.86899],
    ),
    (
        "Be_palik",
        [4.18501, 3.18503, 2.78406],
        [3.83547, 3.01012, 2.86899],
    ),
    ("Cr", [4.36967, 2.91651, 1.6549], [5.20655, 4.23131, 3.7547]),
    ("CsI", [2.1449, 1.70232, 1.66243], [0.0, 0.0, 0.0]),
    ("CsI_palik", [2.1449, 1.70232, 1.66243], [0.0, 0.0, 0.0]),
    (
        "Cu",
        [0.201005, 0.92375, 1.10222],
        [3.91326, 2.45305, 2.14209],
    ),
    (
        "Cu_palik",
        [0.213229, 0.919715, 1.10241],
        [3.92187, 2.45733, 2.13658],
    ),
    (
        "Cu2O",
        [3.55177, 2.94987, 2.75188],
        [0.114207, 0.193897, 0.606134],
    ),
    (
        "Cu2O_palik",
        [3.55177, 2.94987, 2.75188],
        [0.114207, 0.193897, 0.606134],
    ),
    (
        "CuO",
        [3.24754, 2.44781, 2.21022],
        [0.52109, 0.570031, 0.722179],
    ),
    (
        "CuO_palik",
        [3.24754, 2.44781, 2.21022],
        [0.52109, 0.570031, 0.722179],
    ),
    ("d-C", [2.70872, 2.31883, 2.2289], [0.0, 0.0, 0.0]),
    ("d-C_palik", [2.70872, 2.31883, 2.2289], [0.0, 0.0, 0.0]),
    (
        "Hg",
        [2.39894, 1.44003, 0.90957],
        [6.32759, 4.37192, 3.42176],
    ),
    (
        "Hg_palik",
        [2.39894, 1.44003, 0.90957],
        [6.32759, 4.37192, 3.42176],
    ),
    (
        "HgTe",
        [4.77904, 3.2312, 2.6599],
        [1.63161, 1.58081, 1.72929],
    ),
    (
        "HgTe_palik",
        [4.77904, 3.2312, 2.6599],
        [1.63161, 1.58081, 1.72929],
    ),
    (
        "Ir",
        [3.0863, 2.08219, 1.61791],
        [5.59215, 4.06709, 3.26731],
    ),
    (
        "Ir_palik",
        [3.0863, 2.08219, 1.61791],
        [5.59215, 4.06709, 3.26731],
    ),
    (
        "K",
        [0.0640432, 0.0464098, 0.0381849],
        [2.1042, 1.34894, 0.913126],
    ),
    (
        "K_palik",
        [0.0640432, 0.0464098, 0.0381849],
        [2.1042, 1.34894, 0.913126],
    ),
    (
        "Li",
        [0.265791, 0.195618, 0.220949],
        [3.54015, 2.31112, 1.66861],
    ),
    (
        "Li_palik",
        [0.265791, 0.195618, 0.220949],
        [3.54015, 2.31112, 1.66861],
    ),
    (
        "MgO",
        [2.08958, 1.65072, 1.59488],
        [4.3327e-12, 0.0, 2.49865e-11],
    ),
    (
        "MgO_palik",
        [2.08958, 1.65072, 1.59488],
        [4.3327e-12, 0.0, 2.49865e-11],
    ),
    (
        "Mo",
        [4.48397, 3.52513, 2.77631],
        [4.11144, 3.42083, 3.15061],
    ),
    (
        "Mo_palik",
        [4.48397, 3.52513, 2.77631],
        [4.11144, 3.42083, 3.15061],
    ),
    (
        "Na_palik",
        [0.0602694, 0.0561409, 0.0619884],
        [3.17927, 2.11249, 1.57904],
    ),
    (
        "Nb",
        [3.42007, 2.79009, 2.39563],
        [3.44139, 2.73767, 2.57975],
    ),
    (
        "Nb_palik",
        [3.42007, 2.79009, 2.39563],
        [3.44139, 2.73767, 2.57975],
    ),
    (
        "Ni_palik",
        [2.3673, 1.66337, 1.46708],
        [4.49881, 3.05015, 2.34544],
    ),
    (
        "Rh",
        [2.58579, 1.86022, 1.55426],
        [6.78226, 4.70299, 3.97607],
    ),
    (
        "Rh_palik",
        [2.58579, 1.86022, 1.55426],
        [6.78226, 4.70299, 3.97607],
    ),
    (
        "Se",
        [4.05831, 2.84294, 2.82085],
        [0.75405, 0.638444, 0.521808],
    ),
    (
        "Se_palik",
        [4.05831, 2.84294, 2.82085],
        [0.75405, 0.638444, 0.521808],
    ),
    (
        "SiC",
        [3.17234, 2.52597, 2.47937],
        [7.53766e-07, 0.0, 1.01925e-05],
    ),
    (
        "SiC_palik",
        [3.17234, 2.52597, 2.47937],
        [7.53766e-07, 0.0, 1.01925e-05],
    ),
    ("SnTe", [4.52425, 1.98164, 1.28159], [0.0, 0.0, 0.0]),
    ("SnTe_palik", [4.52425, 1.98164, 1.28159], [0.0, 0.0, 0.0]),
    (
        "Ta",
        [2.06272, 2.39294, 2.62793],
        [2.40836, 1.74149, 1.94703],
    ),
    (
        "Ta_palik",
        [2.06272, 2.39294, 2.62793],
        [2.40836, 1.74149, 1.94703],
    ),
    (
        "Te",
        [7.39023, 4.4821, 2.63711],
        [3.25602, 3.52706, 3.29205],
    ),
    (
        "Te_palik",
        [7.39023, 4.4821, 2.63711],
        [3.25602, 3.52706, 3.29205],
    ),
    ("ThF4", [1.83071, 1.44223, 1.38765], [0.0, 0.0, 0.0]),
    ("ThF4_palik", [1.83071, 1.44223, 1.38765], [0.0, 0.0, 0.0]),
    (
        "TiC",
        [3.70053, 2.83742, 2.58229],
        [3.26564, 2.35159, 2.17279],
    ),
    (
        "TiC_palik",
        [3.70053, 2.83742, 2.58229],
        [3.26564, 2.35159, 2.17279],
    ),
    (
        "TiN",
        [1.64845, 1.15052, 1.37982],
        [3.36833, 1.9435, 1.10207],
    ),
    (
        "TiN_palik",
        [1.64845, 1.15052, 1.37982],
        [3.36833, 1.9435, 1.10207],
    ),
    (
        "TiO2",
        [3.45661, 2.80174, 2.90517],
        [0.000105265, 0.0, 0.000652887],
    ),
    (
        "TiO2_palik",
        [3.45661, 2.80174, 2.90517],
        [0.000105265, 0.0, 0.000652887],
    ),
    (
        "VC",
        [3.65757, 2.75274, 2.53267],
        [3.0683, 2.19869, 1.96319],
    ),
    (
        "VC_palik",
        [3.65757, 2.75274, 2.53267],
        [3.0683, 2.19869, 1.96319],
    ),
    (
        "V_palik",
        [4.27758, 3.51295, 2.76107],
        [3.4913, 2.88945, 3.11152],
    ),
    (
        "VN",
        [2.8656, 2.11919, 1.94009],
        [3.03224, 2.05612, 1.61631],
    ),
    (
        "VN_palik",
        [2.8656, 2.11919, 1.94009],
        [3.03224, 2.05612, 1.61631],
    ),
    (
        "W",
        [4.37082, 3.30025, 2.99841],
        [3.50064, 2.60487, 2.27323],
    ),
];

#[cfg(test)]
mod tests {
    use super::*;

    /// A reflectance of 1 at every wavelength under D65 is white; an emission of 1 at every
    /// wavelength has luminance 1 (Y of XYZ (1, 1, 1)).
    #[test]
    fn flat_spectra_give_white_and_unit_luminance() {
        let white = Spectrum::Pairs(vec![(CIE_MIN, 1.0), (CIE_MAX, 1.0)]);
        let rgb = spectrum_to_rgb(&white, SpectrumUse::Bounded);
        assert!((rgb - Color::ONE).abs().max_element() < 2e-3, "{rgb}");
        let emission = spectrum_to_rgb(&white, SpectrumUse::Emission);
        let y = 0.2126 * emission.x + 0.7152 * emission.y + 0.0722 * emission.z;
        assert!((y - 1.0).abs() < 2e-3, "{emission}, luminance {y}");
    }

    /// A spectrum that is zero where the eye sees nothing gives black, and one confined to
    /// long wavelengths is red.
    #[test]
    fn narrow_spectra_have_their_hue() {
        let red = Spectrum::Pairs(vec![(600.0, 1.0), (700.0, 1.0)]);
        let rgb = spectrum_to_rgb(&red, SpectrumUse::Emission);
        assert!(rgb.x > 4.0 * rgb.y && rgb.x > 4.0 * rgb.z, "{rgb}");
        let invisible = Spectrum::Pairs(vec![(800.0, 5.0), (830.0, 5.0)]);
        assert!(spectrum_to_rgb(&invisible, SpectrumUse::Emission).max_element() < 1e-3);
    }

    /// Two spectra of Mitsuba's own render tests, against what Mitsuba 3.9's
    /// `spectrum_list_to_srgb` gives for them (computed with its Python module).
    #[test]
    fn spectra_convert_as_mitsuba_converts_them() {
        let pairs = |v: [f64; 4]| {
            Spectrum::Pairs(vec![
                (400.0, v[0]),
                (500.0, v[1]),
                (600.0, v[2]),
                (700.0, v[3]),
            ])
        };
        let cases = [
            (
                pairs([0.0, 8.0, 15.6, 18.4]),
                SpectrumUse::Emission,
                [20.7108, 10.8546, 2.77115],
            ),
            (
                pairs([0.78; 4]),
                SpectrumUse::Bounded,
                [0.776368, 0.779809, 0.776029],
            ),
        ];
        for (spectrum, usage, expected) in cases {
            let rgb = spectrum_to_rgb(&spectrum, usage);
            for (c, e) in rgb.to_array().into_iter().zip(expected) {
                assert!(
                    (c as f64 / e - 1.0).abs() < 1e-3,
                    "{rgb} against {expected:?}"
                );
            }
        }
    }

    #[test]
    fn named_indices_are_found() {
        assert_eq!(named_ior("bk7"), Some(1.5046));
        assert_eq!(named_ior("glass?"), None);
        let (eta, k) = named_conductor("Au").unwrap();
        // Gold reflects red more than blue.
        assert!(eta.z > eta.x && k.x > k.z);
    }
}
