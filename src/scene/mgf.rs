//! MGF, the Materials and Geometry Format of the radiosity community (Greg Ward 1994–95), read
//! into the same `Scene` the other formats produce: polygons as quads (planar convex quads)
//! or triangles, the primitives (`sph`, `cyl`, `cone`, `ring`, `torus`, `prism`) tessellated
//! as RenderPark does (4 divisions per quarter circle), colours (`cxy`, `cspec`, `cct`,
//! `cmix`) to linear RGB, `ed` emittance to radiance. `xf` transforms with `-a` arrays and
//! `i` includes (relative to the including file, cycles refused) are applied where vertices
//! are used. `docs/scene-format.md` of the project has the support table.
//!
//! Conventions (mgf.md): chromaticity (x, y) with luminance Y gives XYZ, then linear RGB with
//! primaries R (0.640, 0.330), G (0.290, 0.600), B (0.150, 0.060) and an equal-energy white,
//! negative components clipped; `ed E` is radiance E / (183.07 π) per unit of the colour's RGB
//! (183.07 lm/W, RenderPark's luminous efficacy of white). Errors name file:line:column.

use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::{Path, PathBuf};

use super::{Material, Quad, Scene, SceneError};
use crate::color::Color;
use crate::geometry::{quad_normal, quad_off_plane, vec3, Vec3};

/// Divisions of a full circle in the tessellated primitives (RenderPark: 4 per quarter).
const CIRCLE_DIVISIONS: usize = 16;
/// RenderPark's luminous efficacy of white light, lm/W.
const WHITE_EFFICACY: f32 = 183.07;
/// The most faces a scene may produce (arrays and includes multiply them): far above the
/// largest shipped scene (about 60,000), far below what would exhaust memory.
const MAX_FACES: usize = 50_000_000;
/// The most nested includes (a chain longer than this is a cycle the path check missed, e.g.
/// through links).
const MAX_INCLUDE_DEPTH: usize = 64;

/// The ray tracer's mirror and refraction depth on MGF scenes when `--num-bounces` is not
/// given: pbrt's Whitted depth (5), where the course's 0 shows no reflection at all. Their
/// glossy floors and glass reflect: on `cube.mgf`'s default view (floor `rs 0.4`) the photon
/// engine's mean goes from 0.413 to 0.824 against the path tracer's 0.810 (2 gave 0.813), for
/// about 2.8× its time there.
pub const NUM_BOUNCES: u32 = 5;

/// Shadow rays a light on MGF scenes when `-num_shadow_samples` is not given: one, to the
/// light's centre, which also turns on visibility in radiosity's form factors, as RenderPark
/// always computes it; the course's 0 casts no shadow at all. On `cube.mgf` with its
/// specular reflectances removed (all diffuse), the path tracer's mean 0.316: the photon
/// engine's 0.346 with the course's 0, 0.314 with 1 (16 gave 0.313).
pub const SHADOW_SAMPLES: u32 = 1;

/// Reads an MGF file and everything it includes.
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    let mut reader = Reader {
        scene: Scene {
            path: path.to_path_buf(),
            background: Vec3::ZERO,
            // RenderPark's rule for MGF's one-sided surfaces: a ray passes through their backs.
            one_sided_triangles: true,
            render_hints: super::RenderHints {
                num_bounces: Some(NUM_BOUNCES),
                num_shadow_samples: Some(SHADOW_SAMPLES),
                // Hierarchical radiosity at any size: MGF's faces are walls and floors, each
                // too large to show one flat radiosity, and the hierarchical solver splits them
                // where the light changes. Against the path tracer's mean, with one shadow
                // ray: `cube.mgf` without its specular reflectances 0.316, progressive
                // refinement's 0.353 (path 0.316); `office2.mgf` 0.0317 against 0.0408 (path
                // 0.0312).
                hierarchical_radiosity: true,
                ..Default::default()
            },
            ..Scene::default()
        },
        vertices: HashMap::new(),
        current_vertex: None,
        colours: HashMap::new(),
        colour: Chroma::WHITE,
        colour_name: None,
        materials: HashMap::new(),
        material: MaterialDef::default(),
        material_name: String::new(),
        converted: HashMap::new(),
        current_scene_material: None,
        transforms: Vec::new(),
        including: Vec::new(),
        unknown: BTreeMap::new(),
        ignored: HashSet::new(),
        faces: 0,
        degenerate: 0,
    };
    reader.file(path, None)?;
    if reader.degenerate > 0 {
        reader.scene.warnings.push(format!(
            "{}: {} faces of no area were skipped",
            path.display(),
            reader.degenerate
        ));
    }
    let mut ignored: Vec<&String> = reader.ignored.iter().collect();
    ignored.sort();
    for name in ignored {
        let why = if name == "td" {
            "diffuse transmission is not rendered"
        } else {
            "surfaces are one-sided unless the render asks --two-sided"
        };
        reader.scene.warnings.push(format!(
            "{}: MGF `{name}` is read but ignored: {why}",
            path.display()
        ));
    }
    for (name, (file, line)) in &reader.unknown {
        reader.scene.warnings.push(format!(
            "{}:{line}: MGF entity `{name}` is not supported; its lines (this the first) were ignored",
            file.display()
        ));
    }
    Ok(reader.scene)
}

/// One entity: its words, each with its line and column.
#[derive(Clone, Debug)]
struct Entity {
    file: std::rc::Rc<PathBuf>,
    words: Vec<Word>,
}

#[derive(Clone, Debug)]
struct Word {
    text: String,
    line: u32,
    column: u32,
}

/// Splits MGF text into entities: one per line, a trailing `\` continuing it, `#` to the end
/// of the line a comment.
fn entities(file: &Path, text: &str) -> Vec<Entity> {
    let file = std::rc::Rc::new(file.to_path_buf());
    let mut out = Vec::new();
    let mut words: Vec<Word> = Vec::new();
    for (n, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("");
        let (body, continues) = match line.trim_end().strip_suffix('\\') {
            Some(b) => (b, true),
            None => (line, false),
        };
        let mut column = 0usize;
        for piece in body.split_inclusive(char::is_whitespace) {
            let word = piece.trim_end();
            if !word.is_empty() {
                words.push(Word {
                    text: word.to_string(),
                    line: n as u32 + 1,
                    column: column as u32 + 1,
                });
            }
            column += piece.chars().count();
        }
        if !continues && !words.is_empty() {
            out.push(Entity {
                file: file.clone(),
                words: std::mem::take(&mut words),
            });
        }
    }
    if !words.is_empty() {
        out.push(Entity { file, words });
    }
    out
}

/// A chromaticity (CIE 1931 x, y).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Chroma {
    x: f32,
    y: f32,
}

impl Chroma {
    const WHITE: Chroma = Chroma {
        x: 1.0 / 3.0,
        y: 1.0 / 3.0,
    };

    /// Linear RGB of this colour at luminance `luminance`.
    fn rgb(self, luminance: f32) -> Color {
        if self.y <= 1e-6 || luminance == 0.0 {
            return Vec3::ZERO;
        }
        let xyz = [
            self.x / self.y * luminance,
            luminance,
            (1.0 - self.x - self.y) / self.y * luminance,
        ];
        let m = xyz_to_rgb();
        let c = |r: usize| (m[r][0] * xyz[0] + m[r][1] * xyz[1] + m[r][2] * xyz[2]).max(0.0);
        vec3(c(0), c(1), c(2))
    }

    /// From XYZ (any scale).
    fn from_xyz(x: f64, y: f64, z: f64) -> Option<Chroma> {
        let sum = x + y + z;
        (sum > 0.0 && sum.is_finite()).then(|| Chroma {
            x: (x / sum) as f32,
            y: (y / sum) as f32,
        })
    }
}

/// The XYZ → RGB matrix of mgf.md's primaries and equal-energy white: RGB (1, 1, 1) is the
/// white of luminance 1.
fn xyz_to_rgb() -> [[f32; 3]; 3] {
    let prim = [(0.640f64, 0.330f64), (0.290, 0.600), (0.150, 0.060)];
    // Columns: XYZ of each primary at Y = 1, then scaled so that they sum to white (1, 1, 1).
    let col = |(x, y): (f64, f64)| [x / y, 1.0, (1.0 - x - y) / y];
    let p = [col(prim[0]), col(prim[1]), col(prim[2])];
    let m = [
        [p[0][0], p[1][0], p[2][0]],
        [p[0][1], p[1][1], p[2][1]],
        [p[0][2], p[1][2], p[2][2]],
    ];
    let s = solve3(m, [1.0, 1.0, 1.0]);
    let rgb_to_xyz = [
        [m[0][0] * s[0], m[0][1] * s[1], m[0][2] * s[2]],
        [m[1][0] * s[0], m[1][1] * s[1], m[1][2] * s[2]],
        [m[2][0] * s[0], m[2][1] * s[1], m[2][2] * s[2]],
    ];
    let inv = invert3(rgb_to_xyz);
    inv.map(|r| r.map(|v| v as f32))
}

fn det3(m: [[f64; 3]; 3]) -> f64 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

fn invert3(m: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let d = det3(m);
    let c =
        |r0: usize, r1: usize, c0: usize, c1: usize| m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0];
    [
        [c(1, 2, 1, 2) / d, -c(0, 2, 1, 2) / d, c(0, 1, 1, 2) / d],
        [-c(1, 2, 0, 2) / d, c(0, 2, 0, 2) / d, -c(0, 1, 0, 2) / d],
        [c(1, 2, 0, 1) / d, -c(0, 2, 0, 1) / d, c(0, 1, 0, 1) / d],
    ]
}

fn solve3(m: [[f64; 3]; 3], b: [f64; 3]) -> [f64; 3] {
    let inv = invert3(m);
    [0, 1, 2].map(|r| inv[r][0] * b[0] + inv[r][1] * b[1] + inv[r][2] * b[2])
}

/// The CIE 1931 colour-matching functions by the multi-lobe Gaussian fit of Wyman, Sloan &
/// Shirley (2013): within about 1% of the tabulated functions, enough for the chromaticity of
/// a measured spectrum.
fn cie_xyz(lambda: f64) -> [f64; 3] {
    let g = |mu: f64, s1: f64, s2: f64| {
        let t = (lambda - mu) / if lambda < mu { s1 } else { s2 };
        (-0.5 * t * t).exp()
    };
    [
        1.056 * g(599.8, 37.9, 31.0) + 0.362 * g(442.0, 16.0, 26.7) - 0.065 * g(501.1, 20.4, 26.2),
        0.821 * g(568.8, 46.9, 40.5) + 0.286 * g(530.9, 16.3, 31.1),
        1.217 * g(437.0, 11.8, 36.0) + 0.681 * g(459.0, 26.0, 13.8),
    ]
}

/// The chromaticity of a black body at `kelvin` (Planck's law integrated against the
/// colour-matching functions over 380–780 nm).
fn black_body(kelvin: f64) -> Option<Chroma> {
    let (c1, c2) = (3.741_771_852e-16, 1.438_776_877e-2);
    let mut xyz = [0.0f64; 3];
    for k in 0..=400 {
        let lambda_nm = 380.0 + k as f64;
        let l = lambda_nm * 1e-9;
        let radiance = c1 / (l.powi(5) * ((c2 / (l * kelvin)).exp() - 1.0));
        let cmf = cie_xyz(lambda_nm);
        for (s, c) in xyz.iter_mut().zip(cmf) {
            *s += radiance * c;
        }
    }
    Chroma::from_xyz(xyz[0], xyz[1], xyz[2])
}

/// An MGF material as it is being defined: photometric fractions of its colours.
#[derive(Clone, Debug)]
struct MaterialDef {
    rd: (f32, Chroma),
    rs: (f32, Chroma, f32),
    ts: (f32, Chroma, f32),
    ed: (f32, Chroma),
    ior: f32,
    /// Where it is defined: the file (the scene's or one it includes) and the line.
    file: std::rc::Rc<PathBuf>,
    line: u32,
}

impl Default for MaterialDef {
    fn default() -> Self {
        MaterialDef {
            rd: (0.0, Chroma::WHITE),
            rs: (0.0, Chroma::WHITE, 0.0),
            ts: (0.0, Chroma::WHITE, 0.0),
            ed: (0.0, Chroma::WHITE),
            ior: 1.5,
            file: Default::default(),
            line: 0,
        }
    }
}

impl MaterialDef {
    fn to_material(&self) -> Material {
        Material {
            diffuse: self.rd.1.rgb(self.rd.0),
            reflective: self.rs.1.rgb(self.rs.0),
            roughness: self.rs.2,
            transmitted: self.ts.1.rgb(self.ts.0),
            emitted: self.ed.1.rgb(self.ed.0) * (WHITE_EFFICACY * std::f32::consts::PI).recip(),
            ior: self.ior,
            line: self.line,
            ..Material::default()
        }
    }
}

/// A named vertex: a point and an optional normal.
#[derive(Clone, Copy, Debug, Default)]
struct VertexDef {
    p: Vec3,
    n: Option<Vec3>,
}

/// An affine transform: p ↦ m·p + t (m row-major).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Affine {
    m: [[f32; 3]; 3],
    t: Vec3,
}

impl Affine {
    const IDENTITY: Affine = Affine {
        m: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        t: Vec3::ZERO,
    };

    fn linear(&self, v: Vec3) -> Vec3 {
        let m = &self.m;
        vec3(
            m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z,
            m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
            m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z,
        )
    }

    fn point(&self, p: Vec3) -> Vec3 {
        self.linear(p) + self.t
    }

    /// `self` then `next`.
    fn then(&self, next: &Affine) -> Affine {
        let mut m = [[0.0f32; 3]; 3];
        for (r, row) in m.iter_mut().enumerate() {
            for (c, v) in row.iter_mut().enumerate() {
                *v = (0..3).map(|k| next.m[r][k] * self.m[k][c]).sum();
            }
        }
        Affine {
            m,
            t: next.point(self.t),
        }
    }

    fn determinant(&self) -> f32 {
        let m = self.m.map(|r| r.map(|v| v as f64));
        det3(m) as f32
    }

    /// The scale of lengths (cube root of |det|): radii of primitives scale by it.
    fn scale(&self) -> f32 {
        self.determinant().abs().cbrt()
    }

    fn rotation(axis: usize, degrees: f32) -> Affine {
        let (s, c) = degrees.to_radians().sin_cos();
        let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
        let mut m = Affine::IDENTITY.m;
        m[a][a] = c;
        m[a][b] = -s;
        m[b][a] = s;
        m[b][b] = c;
        Affine { m, t: Vec3::ZERO }
    }
}

/// The reader's state: the scene so far and MGF's contexts.
struct Reader {
    scene: Scene,
    vertices: HashMap<String, VertexDef>,
    /// The vertex that `p` and `n` lines set.
    current_vertex: Option<String>,
    colours: HashMap<String, Chroma>,
    /// The current colour and, when it is a named one, its name (`cxy` changes both).
    colour: Chroma,
    colour_name: Option<String>,
    materials: HashMap<String, MaterialDef>,
    material: MaterialDef,
    material_name: String,
    /// Scene materials by the MGF definition they were converted from (its text: equal
    /// definitions share one).
    converted: HashMap<String, u32>,
    /// The scene material of the current MGF material, until the material changes.
    current_scene_material: Option<u32>,
    /// The transforms of the enclosing `xf` blocks and includes, each composed with those
    /// around it (the last is the one in force).
    transforms: Vec<Affine>,
    /// Files being read (include cycle check).
    including: Vec<PathBuf>,
    /// Entities of unknown names, each with where it first appears (file and line).
    unknown: BTreeMap<String, (std::rc::Rc<PathBuf>, u32)>,
    /// Entities read but not rendered (`td`, `sides`).
    ignored: HashSet<String>,
    faces: usize,
    /// Faces (and slivers of triangulated faces) skipped for having no area.
    degenerate: usize,
}

fn syntax(e: &Entity, w: &Word, expected: &str) -> SceneError {
    SceneError::Syntax {
        file: e.file.as_ref().clone(),
        line: w.line,
        column: w.column,
        expected: expected.to_string(),
        found: format!("`{}`", w.text),
    }
}

fn invalid(e: &Entity, w: &Word, message: String) -> SceneError {
    SceneError::Invalid {
        file: e.file.as_ref().clone(),
        line: w.line,
        column: w.column,
        message,
    }
}

/// The end of an entity, for "expected … found the end of the line".
fn missing(e: &Entity, expected: &str) -> SceneError {
    let last = e.words.last().expect("entities have a word");
    SceneError::Syntax {
        file: e.file.as_ref().clone(),
        line: last.line,
        column: last.column + last.text.chars().count() as u32,
        expected: expected.to_string(),
        found: "the end of the line".into(),
    }
}

fn number(e: &Entity, k: usize, what: &str) -> Result<f32, SceneError> {
    let w = e.words.get(k).ok_or_else(|| missing(e, what))?;
    match w.text.parse::<f32>() {
        Ok(v) if super::range::in_range(v) => Ok(v),
        Ok(v) if !v.is_nan() => Err(invalid(
            e,
            w,
            format!("`{}` is out of range: {}", w.text, super::range::RANGE),
        )),
        _ => Err(syntax(e, w, what)),
    }
}

fn count(e: &Entity, k: usize, what: &str) -> Result<usize, SceneError> {
    let w = e.words.get(k).ok_or_else(|| missing(e, what))?;
    w.text.parse::<usize>().map_err(|_| syntax(e, w, what))
}

impl Reader {
    /// The transform of the enclosing `xf` blocks and includes, composed.
    fn transform(&self) -> Affine {
        self.transforms.last().copied().unwrap_or(Affine::IDENTITY)
    }

    /// Runs `f` inside one more transform, `t` applied before the enclosing ones.
    fn within(
        &mut self,
        t: &Affine,
        f: impl FnOnce(&mut Self) -> Result<(), SceneError>,
    ) -> Result<(), SceneError> {
        let composed = t.then(&self.transform());
        self.transforms.push(composed);
        let result = f(self);
        self.transforms.pop();
        result
    }

    /// Reads a file (the first, or an include named by `from`) with the transform in force.
    fn file(&mut self, path: &Path, from: Option<(&Entity, &Word)>) -> Result<(), SceneError> {
        let canonical = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
        if self.including.contains(&canonical) || self.including.len() >= MAX_INCLUDE_DEPTH {
            let (e, w) = from.expect("the first file is never a cycle");
            return Err(invalid(
                e,
                w,
                format!("include cycle: {} includes itself", path.display()),
            ));
        }
        let text = std::fs::read(path).map_err(|source| match from {
            Some((e, w)) => invalid(
                e,
                w,
                format!("cannot open the included file {}: {source}", path.display()),
            ),
            None => SceneError::Io {
                file: path.to_path_buf(),
                source,
            },
        })?;
        let text = String::from_utf8_lossy(&text);
        self.including.push(canonical);
        let list = entities(path, &text);
        let result = self.run(&list);
        self.including.pop();
        result
    }

    /// Interprets a list of entities (a file, or the body of an `xf -a` array, once per copy).
    fn run(&mut self, list: &[Entity]) -> Result<(), SceneError> {
        let mut k = 0;
        while k < list.len() {
            let e = &list[k];
            if e.words[0].text == "xf" && e.words.len() > 1 {
                // The block up to the matching `xf`, run once per copy of its array.
                let end = matching_end(list, k).ok_or_else(|| {
                    invalid(e, &e.words[0], "this xf has no closing `xf` line".into())
                })?;
                let body = &list[k + 1..end];
                for t in xf_transforms(e, 1)? {
                    self.within(&t, |r| r.run(body))?;
                }
                k = end + 1;
                continue;
            }
            self.entity(e)?;
            k += 1;
        }
        Ok(())
    }

    fn entity(&mut self, e: &Entity) -> Result<(), SceneError> {
        let head = &e.words[0];
        match head.text.as_str() {
            "v" => self.vertex(e),
            "p" | "n" => {
                let name = self.current_vertex.clone().ok_or_else(|| {
                    invalid(
                        e,
                        head,
                        format!("`{}` outside a vertex definition (`v NAME =`)", head.text),
                    )
                })?;
                let v = vec3(number(e, 1, "x")?, number(e, 2, "y")?, number(e, 3, "z")?);
                let def = self.vertices.entry(name).or_default();
                if head.text == "p" {
                    def.p = v;
                } else {
                    def.n = Some(v);
                }
                Ok(())
            }
            "c" => self.colour_entity(e),
            "cxy" => {
                let c = Chroma {
                    x: number(e, 1, "the chromaticity x")?,
                    y: number(e, 2, "the chromaticity y")?,
                };
                self.set_colour(c);
                Ok(())
            }
            "cspec" => {
                let (lo, hi) = (
                    number(e, 1, "the first wavelength (nm)")?,
                    number(e, 2, "the last wavelength (nm)")?,
                );
                let values: Vec<f32> = (3..e.words.len())
                    .map(|k| number(e, k, "a spectral value"))
                    .collect::<Result<_, _>>()?;
                if values.len() < 2 || hi <= lo {
                    return Err(invalid(
                        e,
                        head,
                        "cspec needs λmin < λmax and at least two values".into(),
                    ));
                }
                let step = (hi - lo) as f64 / (values.len() - 1) as f64;
                let mut xyz = [0.0f64; 3];
                for (k, &v) in values.iter().enumerate() {
                    let cmf = cie_xyz(lo as f64 + k as f64 * step);
                    for (s, c) in xyz.iter_mut().zip(cmf) {
                        *s += v.max(0.0) as f64 * c;
                    }
                }
                self.set_colour(Chroma::from_xyz(xyz[0], xyz[1], xyz[2]).unwrap_or(Chroma::WHITE));
                Ok(())
            }
            "cct" => {
                let t = number(e, 1, "a colour temperature (K)")?;
                if t <= 0.0 {
                    return Err(invalid(
                        e,
                        &e.words[1],
                        "a colour temperature must be positive".into(),
                    ));
                }
                self.set_colour(black_body(t as f64).unwrap_or(Chroma::WHITE));
                Ok(())
            }
            "cmix" => {
                let (mut x, mut y, mut z) = (0.0f64, 0.0f64, 0.0f64);
                let mut k = 1;
                while k < e.words.len() {
                    let w = number(e, k, "a weight")? as f64;
                    let name = e
                        .words
                        .get(k + 1)
                        .ok_or_else(|| missing(e, "a colour name"))?;
                    let c = *self.colours.get(&name.text).ok_or_else(|| {
                        invalid(e, name, format!("undefined colour `{}`", name.text))
                    })?;
                    if c.y > 1e-6 {
                        x += w * (c.x / c.y) as f64;
                        y += w;
                        z += w * ((1.0 - c.x - c.y) / c.y) as f64;
                    }
                    k += 2;
                }
                self.set_colour(Chroma::from_xyz(x, y, z).unwrap_or(Chroma::WHITE));
                Ok(())
            }
            "m" => self.material_entity(e),
            "rd" => {
                self.material.rd = (number(e, 1, "a diffuse reflectance")?, self.colour);
                self.material_changed();
                Ok(())
            }
            "rs" => {
                self.material.rs = (
                    number(e, 1, "a specular reflectance")?,
                    self.colour,
                    number(e, 2, "a roughness")?,
                );
                self.material_changed();
                Ok(())
            }
            "ts" => {
                self.material.ts = (
                    number(e, 1, "a specular transmittance")?,
                    self.colour,
                    number(e, 2, "a roughness")?,
                );
                self.material_changed();
                Ok(())
            }
            "ed" => {
                self.material.ed = (number(e, 1, "an emittance (lm/m²)")?, self.colour);
                self.material_changed();
                Ok(())
            }
            "ir" => {
                self.material.ior = number(e, 1, "an index of refraction")?;
                self.material_changed();
                Ok(())
            }
            // Read and checked, not rendered: trilux has no diffuse transmission, and
            // sidedness is the render's choice (`--two-sided`), as in RenderPark's default run.
            "td" | "sides" => {
                number(e, 1, "a number")?;
                self.ignored.insert(head.text.clone());
                Ok(())
            }
            "f" => self.face(e),
            "sph" | "cyl" | "cone" | "ring" | "torus" | "prism" => self.primitive(e),
            "i" => self.include(e),
            "xf" => Ok(()), // a closing `xf` whose block was run above; or an empty one
            "o" => Ok(()),
            name => {
                self.unknown
                    .entry(name.to_string())
                    .or_insert_with(|| (e.file.clone(), head.line));
                Ok(())
            }
        }
    }

    fn vertex(&mut self, e: &Entity) -> Result<(), SceneError> {
        let name = e.words.get(1).ok_or_else(|| missing(e, "a vertex name"))?;
        match e.words.get(2).map(|w| w.text.as_str()) {
            Some("=") => {
                let def = match e.words.get(3) {
                    Some(t) => *self
                        .vertices
                        .get(&t.text)
                        .ok_or_else(|| invalid(e, t, format!("undefined vertex `{}`", t.text)))?,
                    None => VertexDef::default(),
                };
                self.vertices.insert(name.text.clone(), def);
                self.current_vertex = Some(name.text.clone());
            }
            None => self.current_vertex = Some(name.text.clone()),
            Some(_) => return Err(syntax(e, &e.words[2], "`=`")),
        }
        Ok(())
    }

    fn set_colour(&mut self, c: Chroma) {
        self.colour = c;
        if let Some(name) = &self.colour_name {
            self.colours.insert(name.clone(), c);
        }
    }

    fn colour_entity(&mut self, e: &Entity) -> Result<(), SceneError> {
        match (e.words.get(1), e.words.get(2).map(|w| w.text.as_str())) {
            (None, _) => {
                self.colour = Chroma::WHITE;
                self.colour_name = None;
            }
            (Some(name), Some("=")) => {
                let c = match e.words.get(3) {
                    Some(t) => *self
                        .colours
                        .get(&t.text)
                        .ok_or_else(|| invalid(e, t, format!("undefined colour `{}`", t.text)))?,
                    None => Chroma::WHITE,
                };
                self.colours.insert(name.text.clone(), c);
                self.colour = c;
                self.colour_name = Some(name.text.clone());
            }
            (Some(name), None) => {
                self.colour = *self
                    .colours
                    .get(&name.text)
                    .ok_or_else(|| invalid(e, name, format!("undefined colour `{}`", name.text)))?;
                self.colour_name = Some(name.text.clone());
            }
            (Some(_), Some(_)) => return Err(syntax(e, &e.words[2], "`=`")),
        }
        Ok(())
    }

    fn material_changed(&mut self) {
        self.current_scene_material = None;
        if !self.material_name.is_empty() {
            self.materials
                .insert(self.material_name.clone(), self.material.clone());
        }
    }

    fn material_entity(&mut self, e: &Entity) -> Result<(), SceneError> {
        self.current_scene_material = None;
        match (e.words.get(1), e.words.get(2).map(|w| w.text.as_str())) {
            (None, _) => {
                self.material = MaterialDef {
                    file: e.file.clone(),
                    line: e.words[0].line,
                    ..MaterialDef::default()
                };
                self.material_name.clear();
            }
            (Some(name), Some("=")) => {
                let def =
                    match e.words.get(3) {
                        Some(t) => self.materials.get(&t.text).cloned().ok_or_else(|| {
                            invalid(e, t, format!("undefined material `{}`", t.text))
                        })?,
                        None => MaterialDef::default(),
                    };
                self.material = MaterialDef {
                    file: e.file.clone(),
                    line: name.line,
                    ..def
                };
                self.material_name = name.text.clone();
                self.materials
                    .insert(name.text.clone(), self.material.clone());
            }
            (Some(name), None) => {
                self.material = self.materials.get(&name.text).cloned().ok_or_else(|| {
                    invalid(e, name, format!("undefined material `{}`", name.text))
                })?;
                self.material_name = name.text.clone();
            }
            (Some(_), Some(_)) => return Err(syntax(e, &e.words[2], "`=`")),
        }
        Ok(())
    }

    /// The scene material of the current MGF material, converted once per definition. A
    /// material whose reflectances add up to more than 1 in some channel (saturated colours
    /// of high luminance do) is scaled down to 1 there, chromaticity kept, with a warning.
    fn scene_material(&mut self) -> u32 {
        if let Some(m) = self.current_scene_material {
            return m;
        }
        let key = format!("{:?}", self.material);
        let index = match self.converted.get(&key) {
            Some(&m) => m,
            None => {
                let m = self.convert_material();
                self.scene.materials.push(m);
                let index = self.scene.materials.len() as u32 - 1;
                self.converted.insert(key, index);
                index
            }
        };
        self.current_scene_material = Some(index);
        index
    }

    /// The current MGF material as a scene material, scaled to conserve energy.
    fn convert_material(&mut self) -> Material {
        let mut m = self.material.to_material();
        let sum = (m.diffuse + m.reflective + m.transmitted).max_element();
        if sum > 1.0 {
            let f = 1.0 / sum;
            // Below 1.001 it is the rounding of an exactly white material: no warning.
            if sum > 1.0 + 1e-3 {
                self.scene.warnings.push(format!(
                    "{}:{}: material `{}` reflects {sum:.3} of the light in one channel; its reflectances are scaled by {f:.3} to conserve energy",
                    self.material.file.display(),
                    self.material.line,
                    self.material_name
                ));
            }
            m.diffuse *= f;
            m.reflective *= f;
            m.transmitted *= f;
        }
        m
    }

    /// A named vertex, transformed to where it is used.
    fn point(&self, e: &Entity, w: &Word, t: &Affine) -> Result<VertexDef, SceneError> {
        let v = self
            .vertices
            .get(&w.text)
            .ok_or_else(|| invalid(e, w, format!("undefined vertex `{}`", w.text)))?;
        Ok(VertexDef {
            p: t.point(v.p),
            n: v.n.map(|n| t.linear(n)),
        })
    }

    fn count_faces(&mut self, e: &Entity, n: usize) -> Result<(), SceneError> {
        self.faces += n;
        if self.faces > MAX_FACES {
            return Err(invalid(
                e,
                &e.words[0],
                format!(
                    "the scene grows past {MAX_FACES} faces (about {} GiB): refused",
                    (MAX_FACES as u64 * 100) >> 30
                ),
            ));
        }
        Ok(())
    }

    fn face(&mut self, e: &Entity) -> Result<(), SceneError> {
        let t = self.transform();
        let mut points: Vec<Vec3> = e.words[1..]
            .iter()
            .map(|w| self.point(e, w, &t).map(|v| v.p))
            .collect::<Result<_, _>>()?;
        if points.len() < 3 {
            return Err(missing(e, "at least three vertices"));
        }
        if t.determinant() < 0.0 {
            points.reverse();
        }
        let material = self.scene_material();
        self.polygon(e, &points, material)
    }

    /// A polygon as one quad (planar and convex) or its triangles (N − 2); a polygon of no
    /// area, and the slivers of no area its triangulation leaves, are skipped (counted), as
    /// RenderPark does.
    fn polygon(&mut self, e: &Entity, points: &[Vec3], material: u32) -> Result<(), SceneError> {
        // Values in range can leave it once transformed (`xf -s`, `-t`) or made into a
        // primitive's polygons (a sphere's centre plus its radius).
        for p in points {
            super::range::check_coordinate(*p, "a vertex (transformed)")
                .map_err(|m| invalid(e, &e.words[0], m))?;
        }
        let size = points
            .iter()
            .map(|p| (*p - points[0]).length())
            .fold(0.0f32, f32::max);
        let area = newell_normal(points).length();
        // NaN (non-finite vertices) counts as no area too.
        if area.is_nan() || area <= AREA_EPSILON * size * size {
            self.degenerate += 1;
            return Ok(());
        }
        if points.len() == 4 {
            let v = [points[0], points[1], points[2], points[3]];
            if convex_planar_quad(&v) {
                self.count_faces(e, 1)?;
                self.scene.quads.push(Quad::new(v, None, material));
                return Ok(());
            }
        }
        let triangles = triangulate(points);
        self.count_faces(e, triangles.len())?;
        for [a, b, c] in triangles {
            let v = [points[a], points[b], points[c]];
            if (v[1] - v[0]).cross(v[2] - v[0]).length() > AREA_EPSILON * size * size {
                self.triangle(v, material);
            } else {
                self.degenerate += 1;
            }
        }
        Ok(())
    }

    fn triangle(&mut self, v: [Vec3; 3], material: u32) {
        let mesh = &mut self.scene.triangles;
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(v);
        mesh.indices.push([base, base + 1, base + 2]);
        mesh.materials.push(material);
    }

    fn primitive(&mut self, e: &Entity) -> Result<(), SceneError> {
        let t = self.transform();
        let kind = e.words[0].text.as_str();
        let vertex = |k: usize, what: &str| -> Result<VertexDef, SceneError> {
            let w = e.words.get(k).ok_or_else(|| missing(e, what))?;
            self.point(e, w, &t)
        };
        let scale = t.scale();
        let mirrored = t.determinant() < 0.0;
        let polygons: Vec<Vec<Vec3>> = match kind {
            "sph" => {
                let c = vertex(1, "the centre vertex")?;
                sphere(c.p, number(e, 2, "a radius")? * scale)
            }
            "cyl" | "cone" => {
                let a = vertex(1, "the first end's vertex")?;
                let r1 = number(e, 2, "a radius")? * scale;
                let (b, r2) = if kind == "cyl" {
                    (vertex(3, "the second end's vertex")?, r1)
                } else {
                    (
                        vertex(3, "the second end's vertex")?,
                        number(e, 4, "a radius")? * scale,
                    )
                };
                cone(a.p, r1, b.p, r2)
            }
            "ring" | "torus" => {
                let c = vertex(1, "the centre vertex")?;
                let axis = c.n.ok_or_else(|| {
                    invalid(
                        e,
                        &e.words[1],
                        format!("a {kind}'s vertex needs a normal (`n`) for its axis"),
                    )
                })?;
                let (r1, r2) = (
                    number(e, 2, "the inner radius")? * scale,
                    number(e, 3, "the outer radius")? * scale,
                );
                if kind == "ring" {
                    ring(c.p, axis, r1, r2)
                } else {
                    torus(c.p, axis, r1, r2)
                }
            }
            _ => {
                // prism V1 … VN LENGTH (the length last, as MGF 2.0 and the shipped files
                // write it): the polygon, its copy moved along its normal, the sides.
                let last = e.words.len() - 1;
                let h = number(e, last, "the prism's length")? * scale;
                let base: Vec<Vec3> = (1..last)
                    .map(|k| vertex(k, "a vertex").map(|v| v.p))
                    .collect::<Result<_, _>>()?;
                if base.len() < 3 {
                    return Err(missing(e, "at least three vertices"));
                }
                prism(&base, h)
            }
        };
        let material = self.scene_material();
        for mut p in polygons {
            if mirrored {
                p.reverse();
            }
            self.polygon(e, &p, material)?;
        }
        Ok(())
    }

    fn include(&mut self, e: &Entity) -> Result<(), SceneError> {
        let name = e.words.get(1).ok_or_else(|| missing(e, "a file name"))?;
        let dir = e.file.parent().map(Path::to_path_buf).unwrap_or_default();
        let path = dir.join(&name.text);
        for t in xf_transforms(e, 2)? {
            self.within(&t, |r| r.file(&path, Some((e, name))))?;
        }
        Ok(())
    }
}

/// The index of the `xf` line that closes the block opened at `open`.
fn matching_end(list: &[Entity], open: usize) -> Option<usize> {
    let mut depth = 0usize;
    for (k, e) in list.iter().enumerate().skip(open) {
        if e.words[0].text == "xf" {
            if e.words.len() > 1 {
                depth += 1;
            } else {
                depth -= 1;
                if depth == 0 {
                    return Some(k);
                }
            }
        }
    }
    None
}

/// The transforms of the `xf` arguments of `e` from word `first` on: one per copy of its `-a`
/// arrays (each argument after `-a N` applied k times to copy k), left to right.
fn xf_transforms(e: &Entity, first: usize) -> Result<Vec<Affine>, SceneError> {
    // Groups: the arguments outside arrays (count 1) and each array's (count N).
    let mut groups: Vec<(Option<usize>, Vec<Affine>)> = vec![(None, Vec::new())];
    let mut k = first;
    let mut copies = 1usize;
    while k < e.words.len() {
        let w = &e.words[k];
        let arg = |j: usize, what: &str| number(e, k + j, what);
        let step = match w.text.as_str() {
            "-t" => {
                let t = Affine {
                    t: vec3(arg(1, "dx")?, arg(2, "dy")?, arg(3, "dz")?),
                    ..Affine::IDENTITY
                };
                k += 4;
                t
            }
            "-rx" | "-ry" | "-rz" => {
                let axis = (w.text.as_bytes()[2] - b'x') as usize;
                let t = Affine::rotation(axis, arg(1, "an angle in degrees")?);
                k += 2;
                t
            }
            "-s" => {
                let s = arg(1, "a scale factor")?;
                if s == 0.0 {
                    return Err(invalid(
                        e,
                        &e.words[k + 1],
                        "a scale of 0 makes the transform singular".into(),
                    ));
                }
                k += 2;
                Affine {
                    m: [[s, 0.0, 0.0], [0.0, s, 0.0], [0.0, 0.0, s]],
                    ..Affine::IDENTITY
                }
            }
            "-mx" | "-my" | "-mz" => {
                let axis = (w.text.as_bytes()[2] - b'x') as usize;
                let mut m = Affine::IDENTITY.m;
                m[axis][axis] = -1.0;
                k += 1;
                Affine { m, t: Vec3::ZERO }
            }
            "-a" => {
                let n = count(e, k + 1, "a number of copies")?;
                copies = copies.saturating_mul(n.max(1));
                if copies > MAX_FACES {
                    return Err(invalid(
                        e,
                        w,
                        format!("{copies} copies: refused (at most {MAX_FACES})"),
                    ));
                }
                groups.push((Some(n), Vec::new()));
                k += 2;
                continue;
            }
            "-i" => {
                // The arguments that follow apply once (ends the array).
                groups.push((None, Vec::new()));
                k += 1;
                continue;
            }
            _ => {
                return Err(syntax(
                    e,
                    w,
                    "a transform argument (-t, -rx, -ry, -rz, -s, -mx, -my, -mz, -a, -i)",
                ))
            }
        };
        groups.last_mut().expect("a group").1.push(step);
    }
    // Every combination of array indices, in order (the first array varies slowest).
    let mut out = vec![Affine::IDENTITY];
    for (array, steps) in &groups {
        let one = steps.iter().fold(Affine::IDENTITY, |acc, s| acc.then(s));
        out = match array {
            // Plain arguments apply once to every copy so far.
            None => out.iter().map(|b| b.then(&one)).collect(),
            // Copy k of an array has its arguments applied k times.
            Some(n) => {
                let mut next = Vec::with_capacity(out.len() * n);
                for base in &out {
                    let mut t = *base;
                    for _ in 0..*n {
                        next.push(t);
                        t = t.then(&one);
                    }
                }
                next
            }
        };
    }
    if out
        .iter()
        .any(|t| t.determinant() == 0.0 || !t.determinant().is_finite())
    {
        return Err(invalid(e, &e.words[0], "the transform is singular".into()));
    }
    Ok(out)
}

/// Whether four points make a planar, convex quad (counter-clockwise about its normal).
fn convex_planar_quad(v: &[Vec3; 4]) -> bool {
    let n = quad_normal(v);
    let size = (v[2] - v[0]).length().max((v[3] - v[1]).length());
    let len = n.length();
    if len.is_nan() || len <= 1e-12 * size * size {
        return false;
    }
    let unit = n * len.recip();
    let planar = quad_off_plane(v, unit, size).is_none();
    let convex = (0..4).all(|k| {
        let (a, b, c) = (v[k], v[(k + 1) % 4], v[(k + 2) % 4]);
        (b - a).cross(c - b).dot(unit) > 0.0
    });
    planar && convex
}

/// Twice the area vector of a polygon (Newell's method: robust for non-planar and concave
/// polygons).
fn newell_normal(points: &[Vec3]) -> Vec3 {
    let n = points.len();
    let mut normal = Vec3::ZERO;
    for k in 0..n {
        let (a, b) = (points[k], points[(k + 1) % n]);
        normal += vec3(
            (a.y - b.y) * (a.z + b.z),
            (a.z - b.z) * (a.x + b.x),
            (a.x - b.x) * (a.y + b.y),
        );
    }
    normal
}

/// Faces whose area is below this times their size² are degenerate and skipped.
const AREA_EPSILON: f32 = 1e-9;

/// Triangles of a polygon, counter-clockwise about its Newell normal, by ear clipping in its
/// plane (mapbox's earcut: N − 2 triangles of a simple polygon; fewer where it drops
/// repeated and collinear vertices). MGF writes a wall with a window as one polygon whose
/// outline runs along a seam to the window and round it (office3's window wall: ten
/// vertices, one repeated); a plain ear clipper found no ear there and fell back to a fan,
/// which covered the window and folded over itself (20.9 m² of triangles for a 7.7 m² wall).
fn triangulate(points: &[Vec3]) -> Vec<[usize; 3]> {
    let (u, v) = frame(newell_normal(points).normalize_or_zero());
    // In f64, as earcut's own tests run it: the plane's coordinates of nearly coincident
    // vertices keep their order.
    let plane: Vec<[f64; 2]> = points
        .iter()
        .map(|p| [p.dot(u) as f64, p.dot(v) as f64])
        .collect();
    let mut indices: Vec<u32> = Vec::new();
    earcut::Earcut::new().earcut(plane.iter().copied(), &[] as &[u32], &mut indices);
    indices
        .chunks_exact(3)
        .map(|t| {
            let [a, b, c] = [t[0] as usize, t[1] as usize, t[2] as usize];
            let (pa, pb, pc) = (plane[a], plane[b], plane[c]);
            let turn = (pb[0] - pa[0]) * (pc[1] - pa[1]) - (pb[1] - pa[1]) * (pc[0] - pa[0]);
            // earcut's winding is its own; the face's is its normal's.
            if turn < 0.0 {
                [a, c, b]
            } else {
                [a, b, c]
            }
        })
        .collect()
}

/// Two unit vectors completing the unit `axis` to a right-handed frame.
fn frame(axis: Vec3) -> (Vec3, Vec3) {
    let helper = if axis.x.abs() < 0.9 {
        vec3(1.0, 0.0, 0.0)
    } else {
        vec3(0.0, 1.0, 0.0)
    };
    let u = helper.cross(axis).normalize_or_zero();
    (u, axis.cross(u))
}

fn circle(centre: Vec3, u: Vec3, v: Vec3, r: f32, k: usize) -> Vec3 {
    let a = std::f32::consts::TAU * k as f32 / CIRCLE_DIVISIONS as f32;
    centre + (u * a.cos() + v * a.sin()) * r
}

/// A sphere as 16 × 8 faces (triangles at the poles); a negative radius faces inward.
fn sphere(c: Vec3, r: f32) -> Vec<Vec<Vec3>> {
    let rows = CIRCLE_DIVISIONS / 2;
    let point = |i: usize, j: usize| {
        let theta = std::f32::consts::PI * j as f32 / rows as f32;
        let phi = std::f32::consts::TAU * i as f32 / CIRCLE_DIVISIONS as f32;
        c + vec3(
            theta.sin() * phi.cos(),
            theta.sin() * phi.sin(),
            theta.cos(),
        ) * r.abs()
    };
    let mut out = Vec::new();
    for j in 0..rows {
        for i in 0..CIRCLE_DIVISIONS {
            let (a, b, cc, d) = (
                point(i, j),
                point(i, j + 1),
                point(i + 1, j + 1),
                point(i + 1, j),
            );
            let mut face = if j == 0 {
                vec![a, b, cc]
            } else if j == rows - 1 {
                vec![a, b, d]
            } else {
                vec![a, b, cc, d]
            };
            if r < 0.0 {
                face.reverse();
            }
            out.push(face);
        }
    }
    out
}

/// The side of a cone (a cylinder when r1 = r2) from `a` to `b`, 16 faces; outward for
/// positive radii.
fn cone(a: Vec3, r1: f32, b: Vec3, r2: f32) -> Vec<Vec<Vec3>> {
    let axis = (b - a).normalize_or_zero();
    let (u, v) = frame(axis);
    let inward = r1 < 0.0 || r2 < 0.0;
    (0..CIRCLE_DIVISIONS)
        .map(|k| {
            let (p0, p1) = (
                circle(a, u, v, r1.abs(), k),
                circle(a, u, v, r1.abs(), k + 1),
            );
            let (q0, q1) = (
                circle(b, u, v, r2.abs(), k),
                circle(b, u, v, r2.abs(), k + 1),
            );
            let mut face = if r1 == 0.0 {
                vec![a, q0, q1]
            } else if r2 == 0.0 {
                vec![p0, p1, b]
            } else {
                vec![p0, p1, q1, q0]
            };
            if inward {
                face.reverse();
            }
            face
        })
        .collect()
}

/// An annulus (a disk when r1 = 0) around `axis`, 16 faces, facing along `axis`.
fn ring(c: Vec3, axis: Vec3, r1: f32, r2: f32) -> Vec<Vec<Vec3>> {
    let axis = axis.normalize_or_zero();
    let (u, v) = frame(axis);
    (0..CIRCLE_DIVISIONS)
        .map(|k| {
            let (o0, o1) = (circle(c, u, v, r2, k), circle(c, u, v, r2, k + 1));
            if r1 <= 0.0 {
                vec![c, o0, o1]
            } else {
                vec![circle(c, u, v, r1, k), o0, o1, circle(c, u, v, r1, k + 1)]
            }
        })
        .collect()
}

/// A torus around `axis` between radii r1 and r2 (tube radius (r2 − r1)/2), 16 × 16 faces.
fn torus(c: Vec3, axis: Vec3, r1: f32, r2: f32) -> Vec<Vec<Vec3>> {
    let axis = axis.normalize_or_zero();
    let (u, v) = frame(axis);
    let (major, minor) = ((r1 + r2) / 2.0, (r2 - r1).abs() / 2.0);
    let point = |i: usize, j: usize| {
        let phi = std::f32::consts::TAU * i as f32 / CIRCLE_DIVISIONS as f32;
        let theta = std::f32::consts::TAU * j as f32 / CIRCLE_DIVISIONS as f32;
        let radial = u * phi.cos() + v * phi.sin();
        c + radial * (major + minor * theta.cos()) + axis * (minor * theta.sin())
    };
    let mut out = Vec::new();
    for i in 0..CIRCLE_DIVISIONS {
        for j in 0..CIRCLE_DIVISIONS {
            out.push(vec![
                point(i, j),
                point(i + 1, j),
                point(i + 1, j + 1),
                point(i, j + 1),
            ]);
        }
    }
    out
}

/// A prism: the base polygon reversed (facing down), its copy moved by `h` along the base's
/// normal, and a quad per side.
fn prism(base: &[Vec3], h: f32) -> Vec<Vec<Vec3>> {
    let n = base.len();
    let mut normal = Vec3::ZERO;
    for k in 0..n {
        normal += (base[k] - base[0]).cross(base[(k + 1) % n] - base[0]);
    }
    let offset = normal.normalize_or_zero() * h;
    let top: Vec<Vec3> = base.iter().map(|&p| p + offset).collect();
    let mut out = vec![base.iter().rev().copied().collect::<Vec<_>>(), top.clone()];
    for k in 0..n {
        let j = (k + 1) % n;
        out.push(vec![base[k], base[j], top[j], top[k]]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_energy_white_is_rgb_one_and_primaries_are_pure() {
        let white = Chroma::WHITE.rgb(1.0);
        for c in white.to_array() {
            // Measured 2.4e-7 (two f32 spacings); the bound is ten times that.
            assert!((c - 1.0).abs() < 2.4e-6, "{white:?}");
        }
        let red = Chroma { x: 0.64, y: 0.33 }.rgb(1.0);
        assert!(
            red.x > 0.0 && red.y.abs() < 1e-5 && red.z.abs() < 1e-5,
            "{red:?}"
        );
    }

    #[test]
    fn a_flat_spectrum_is_nearly_white_and_a_warm_body_is_reddish() {
        let xyz = (0..=40).fold([0.0f64; 3], |mut s, k| {
            let c = cie_xyz(380.0 + 10.0 * k as f64);
            for (a, b) in s.iter_mut().zip(c) {
                *a += b;
            }
            s
        });
        let c = Chroma::from_xyz(xyz[0], xyz[1], xyz[2]).unwrap();
        assert!(
            (c.x - 1.0 / 3.0).abs() < 0.01 && (c.y - 1.0 / 3.0).abs() < 0.01,
            "{c:?}"
        );
        // Planck's locus at 2856 K (illuminant A): x ≈ 0.4476, y ≈ 0.4074.
        let a = black_body(2856.0).unwrap();
        assert!(
            (a.x - 0.4476).abs() < 0.01 && (a.y - 0.4074).abs() < 0.01,
            "{a:?}"
        );
    }

    #[test]
    fn a_concave_polygon_triangulates_inside_itself() {
        // An L: six vertices, four triangles, total area 3.
        let l = [
            vec3(0.0, 0.0, 0.0),
            vec3(2.0, 0.0, 0.0),
            vec3(2.0, 1.0, 0.0),
            vec3(1.0, 1.0, 0.0),
            vec3(1.0, 2.0, 0.0),
            vec3(0.0, 2.0, 0.0),
        ];
        let t = triangulate(&l);
        assert_eq!(t.len(), 4);
        let area: f32 = t
            .iter()
            .map(|&[a, b, c]| (l[b] - l[a]).cross(l[c] - l[a]).z / 2.0)
            .sum();
        // Measured exactly 3; the bound is ten f32 spacings at 3.
        assert!((area - 3.0).abs() < 2.4e-6, "{area}");
        assert!(t
            .iter()
            .all(|&[a, b, c]| (l[b] - l[a]).cross(l[c] - l[a]).z > 0.0));
    }

    #[test]
    fn a_wall_whose_window_is_joined_by_a_seam_triangulates_around_the_window() {
        // office3's window wall (office.mgf, in its own units): the outline, then along the
        // window's bottom edge to the window and round it, back along the same edge.
        let xy = [
            (30.0, 15.5),
            (-30.0, 15.5),
            (-30.0, 51.0),
            (30.0, 51.0),
            (30.0, 26.0),
            (23.5, 26.0),
            (23.5, 43.0),
            (-23.5, 43.0),
            (-23.5, 26.0),
            (30.0, 26.0),
        ];
        let wall: Vec<Vec3> = xy.iter().map(|&(x, y)| vec3(x, y, 30.0)).collect();
        let normal = newell_normal(&wall).normalize();
        let t = triangulate(&wall);
        assert_eq!(t.len(), wall.len() - 2);
        let areas: Vec<f32> = t
            .iter()
            .map(|&[a, b, c]| (wall[b] - wall[a]).cross(wall[c] - wall[a]).dot(normal) / 2.0)
            .collect();
        // Every triangle faces the wall's way, and together they cover the wall less the
        // window once: 60 × 35.5 − 47 × 17 = 1331 (the fan before covered 3,601 in all).
        assert!(areas.iter().all(|&a| a >= 0.0), "{areas:?}");
        let area: f32 = areas.iter().sum();
        assert!((area - 1331.0).abs() < 1e-3, "{area}");
        // None reaches into the window.
        for &[a, b, c] in &t {
            let centroid = (wall[a] + wall[b] + wall[c]) / 3.0;
            let in_window = centroid.x.abs() < 23.5 && centroid.y > 26.0 && centroid.y < 43.0;
            assert!(!in_window, "{centroid:?}");
        }
    }

    #[test]
    fn arrays_give_each_copy_its_multiple_of_the_step() {
        let e = &entities(Path::new("t.mgf"), "xf -a 3 -t 1 0 0")[0];
        let t = xf_transforms(e, 1).unwrap();
        let xs: Vec<f32> = t.iter().map(|t| t.point(Vec3::ZERO).x).collect();
        assert_eq!(xs, vec![0.0, 1.0, 2.0]);
        let e = &entities(Path::new("t.mgf"), "xf -t 5 0 0 -a 2 -ry 180")[0];
        let t = xf_transforms(e, 1).unwrap();
        let p: Vec<Vec3> = t.iter().map(|t| t.point(vec3(1.0, 0.0, 0.0))).collect();
        assert!(
            (p[0].x - 6.0).abs() < 1e-5 && (p[1].x + 6.0).abs() < 1e-4,
            "{p:?}"
        );
    }
}
