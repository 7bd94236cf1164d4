//! The course dialect: a token stream extending Wavefront OBJ with materials, spheres, rings,
//! a background colour and a camera (see docs/scene-format.md).

use std::path::{Path, PathBuf};

use super::error::SceneError;
use super::medium::Medium;
use super::procedural::{Bump, BumpSource, Pattern, ProceduralTexture, BUMP_PATTERNS};
use super::sky::{Sky, SkyMap};
use super::{Material, Quad, Scene, ShapePrim};
use crate::camera::{Camera, Projection};
use crate::color::srgb_to_linear;
use crate::geometry::{
    quad_normal, quad_off_plane, vec2, vec3, RingShape, SphereShape, Vec2, Vec3,
};
use std::sync::Arc;

/// Whether `text` is in the course dialect: some line starts with one of the dialect's own
/// tokens. `s` counts only with four numbers after it, since standard OBJ uses `s` for
/// smoothing groups (`s off`, `s 1`).
pub fn is_dialect(text: &str) -> bool {
    text.lines().any(|line| {
        let line = line.split('#').next().unwrap_or("");
        let mut words = line.split_whitespace();
        match words.next() {
            Some(
                "material" | "m" | "r" | "PerspectiveCamera" | "OrthographicCamera"
                | "background_color",
            ) => true,
            Some("s") => {
                let rest: Vec<&str> = words.collect();
                rest.len() == 4 && rest.iter().all(|w| w.parse::<f32>().is_ok())
            }
            _ => false,
        }
    })
}

#[derive(Clone, Copy)]
struct Token<'a> {
    text: &'a str,
    line: u32,
    column: u32,
}

/// Splits the text into whitespace-separated tokens, dropping `#` comments.
struct Lexer<'a> {
    rest: &'a str,
    line: u32,
    column: u32,
}

impl<'a> Lexer<'a> {
    fn new(text: &'a str) -> Self {
        Lexer {
            rest: text,
            line: 1,
            column: 1,
        }
    }

    fn advance(&mut self, bytes: usize) {
        for c in self.rest[..bytes].chars() {
            if c == '\n' {
                self.line += 1;
                self.column = 1;
            } else {
                self.column += 1;
            }
        }
        self.rest = &self.rest[bytes..];
    }

    fn next_token(&mut self) -> Option<Token<'a>> {
        loop {
            let skip = self
                .rest
                .find(|c: char| !c.is_whitespace())
                .unwrap_or(self.rest.len());
            self.advance(skip);
            if self.rest.starts_with('#') {
                let end = self.rest.find('\n').unwrap_or(self.rest.len());
                self.advance(end);
                continue;
            }
            break;
        }
        if self.rest.is_empty() {
            return None;
        }
        let end = self
            .rest
            .find(|c: char| c.is_whitespace() || c == '#')
            .unwrap_or(self.rest.len());
        let token = Token {
            text: &self.rest[..end],
            line: self.line,
            column: self.column,
        };
        self.advance(end);
        Some(token)
    }
}

struct Parser<'a> {
    file: PathBuf,
    lexer: Lexer<'a>,
    peeked: Option<Option<Token<'a>>>,
    /// Where the last token ended, for errors at the end of the file.
    last: (u32, u32),
}

const MEDIUM_KEYS: [&str; 3] = ["sigma_a", "sigma_s", "g"];

const MATERIAL_KEYS: [&str; 15] = [
    "diffuse",
    "texture_file",
    "reflective",
    "emitted",
    "transmitted",
    "ior",
    "roughness",
    "interior_medium",
    "texture_procedural",
    "texture_scale",
    "texture_colors",
    "bump_procedural",
    "bump_file",
    "bump_amplitude",
    "bump_scale",
];

/// The keys of a material's procedural texture and bump map as read, checked together at
/// the end of the material (the keys may come in any order).
#[derive(Default)]
struct PatternKeys<'a> {
    texture: Option<(Pattern, Token<'a>)>,
    texture_scale: Option<(f32, Token<'a>)>,
    texture_colors: Option<([Vec3; 2], Token<'a>)>,
    bump_pattern: Option<(Pattern, Token<'a>)>,
    bump_file: Option<(PathBuf, Token<'a>)>,
    bump_amplitude: Option<(f32, Token<'a>)>,
    bump_scale: Option<(f32, Token<'a>)>,
}

impl<'a> PatternKeys<'a> {
    /// Reads the value of one of the pattern keys (`key` already read).
    fn read(&mut self, p: &mut Parser<'a>, key: Token<'a>) -> Result<(), SceneError> {
        let positive = |p: &mut Parser<'a>, what: &str| -> Result<(f32, Token<'a>), SceneError> {
            let x = p.real(what)?;
            if x <= 0.0 {
                return Err(p.invalid(key, format!("{} must be > 0, found {x}", key.text)));
            }
            Ok((x, key))
        };
        match key.text {
            "texture_procedural" | "bump_procedural" => {
                let allowed: Vec<Pattern> = if key.text == "bump_procedural" {
                    BUMP_PATTERNS.to_vec()
                } else {
                    Pattern::NAMES.iter().map(|&(_, p)| p).collect()
                };
                let names = allowed
                    .iter()
                    .map(|p| p.name())
                    .collect::<Vec<_>>()
                    .join(" | ");
                let t = p.next();
                let pattern = t
                    .and_then(|t| Pattern::from_name(t.text))
                    .filter(|p| allowed.contains(p))
                    .ok_or_else(|| p.syntax(t, &format!("a pattern ({} {names})", key.text)))?;
                *(if key.text == "bump_procedural" {
                    &mut self.bump_pattern
                } else {
                    &mut self.texture
                }) = Some((pattern, key));
            }
            "texture_scale" => {
                self.texture_scale = Some(positive(p, "a real number (texture_scale s)")?)
            }
            "bump_scale" => self.bump_scale = Some(positive(p, "a real number (bump_scale s)")?),
            "bump_amplitude" => {
                self.bump_amplitude = Some((p.real("a real number (bump_amplitude a)")?, key))
            }
            "texture_colors" => {
                let what = "a real number (texture_colors r g b  r g b)";
                let colors = [p.vec3(what)?, p.vec3(what)?];
                if colors
                    .iter()
                    .any(|c| c.min_element() < 0.0 || c.max_element() > 1.0)
                {
                    return Err(p.invalid(
                        key,
                        "texture_colors are albedos: each channel must lie in [0, 1]".into(),
                    ));
                }
                self.texture_colors = Some((colors, key));
            }
            _ => {
                let name = p
                    .next()
                    .ok_or_else(|| p.syntax(None, "a file name (bump_file f)"))?;
                self.bump_file = Some((PathBuf::from(name.text), key));
            }
        }
        Ok(())
    }

    /// Puts the texture and bump map into `m`, or says which keys do not go together.
    fn apply(self, p: &Parser, m: &mut Material) -> Result<(), SceneError> {
        let needs = |given: Option<Token>, what: &str| match given {
            Some(at) => {
                Err(p.invalid(at, format!("{} needs {what} in the same material", at.text)))
            }
            None => Ok(()),
        };
        match self.texture {
            Some((pattern, at)) => {
                if m.texture_file.is_some() {
                    return Err(p.invalid(
                        at,
                        "a material takes texture_procedural or texture_file, not both".into(),
                    ));
                }
                let mut t = ProceduralTexture::new(pattern);
                if let Some((scale, _)) = self.texture_scale {
                    t.scale = scale;
                }
                if let Some((colors, _)) = self.texture_colors {
                    t.colors = colors;
                }
                m.procedural = Some(t);
            }
            None => {
                needs(self.texture_scale.map(|k| k.1), "texture_procedural")?;
                needs(self.texture_colors.map(|k| k.1), "texture_procedural")?;
            }
        }
        let source = match (self.bump_pattern, self.bump_file) {
            (Some(_), Some((_, at))) => {
                return Err(p.invalid(
                    at,
                    "a material takes bump_procedural or bump_file, not both".into(),
                ))
            }
            (Some((pattern, _)), None) => Some(BumpSource::Procedural {
                pattern,
                scale: self.bump_scale.map_or(1.0, |k| k.0),
                origin: Vec3::ZERO,
            }),
            (None, Some((file, _))) => {
                needs(self.bump_scale.map(|k| k.1), "bump_procedural")?;
                Some(BumpSource::File { file, map: None })
            }
            (None, None) => {
                needs(self.bump_scale.map(|k| k.1), "bump_procedural")?;
                needs(
                    self.bump_amplitude.map(|k| k.1),
                    "bump_procedural or bump_file",
                )?;
                None
            }
        };
        m.bump = source.map(|source| Bump {
            source,
            amplitude: self.bump_amplitude.map_or(0.01, |k| k.0),
        });
        Ok(())
    }
}

impl<'a> Parser<'a> {
    fn next(&mut self) -> Option<Token<'a>> {
        let t = match self.peeked.take() {
            Some(t) => t,
            None => self.lexer.next_token(),
        };
        if let Some(t) = t {
            self.last = (t.line, t.column);
        }
        t
    }

    fn peek(&mut self) -> Option<Token<'a>> {
        if self.peeked.is_none() {
            self.peeked = Some(self.lexer.next_token());
        }
        self.peeked.flatten()
    }

    fn syntax(&self, at: Option<Token>, expected: &str) -> SceneError {
        let (line, column, found) = match at {
            Some(t) => (t.line, t.column, format!("`{}`", t.text)),
            None => (self.last.0, self.last.1, "the end of the file".to_string()),
        };
        SceneError::Syntax {
            file: self.file.clone(),
            line,
            column,
            expected: expected.to_string(),
            found,
        }
    }

    fn invalid(&self, at: Token, message: String) -> SceneError {
        SceneError::Invalid {
            file: self.file.clone(),
            line: at.line,
            column: at.column,
            message,
        }
    }

    fn real(&mut self, what: &str) -> Result<f32, SceneError> {
        let t = self.next();
        match (t, t.map(|t| t.text.parse::<f32>())) {
            (_, Some(Ok(x))) if super::range::in_range(x) => Ok(x),
            (Some(tok), Some(Ok(x))) if !x.is_nan() => Err(self.invalid(
                tok,
                format!("`{}` is out of range: {}", tok.text, super::range::RANGE),
            )),
            _ => Err(self.syntax(t, what)),
        }
    }

    fn vec3(&mut self, what: &str) -> Result<Vec3, SceneError> {
        Ok(vec3(self.real(what)?, self.real(what)?, self.real(what)?))
    }

    fn index(&mut self, what: &str) -> Result<(i64, Token<'a>), SceneError> {
        let t = self.next();
        match t.map(|t| (t.text.parse::<i64>(), t)) {
            Some((Ok(k), tok)) => Ok((k, tok)),
            _ => Err(self.syntax(t, what)),
        }
    }

    fn expect(&mut self, text: &str) -> Result<Token<'a>, SceneError> {
        match self.next() {
            Some(t) if t.text == text => Ok(t),
            other => Err(self.syntax(other, &format!("`{text}`"))),
        }
    }
}

/// `c` if no channel is negative, else an error at `at`: radiance is never negative.
fn non_negative(p: &Parser, at: Token, c: Vec3) -> Result<Vec3, SceneError> {
    if c.min_element() < 0.0 {
        return Err(p.invalid(at, format!("{}: radiance must be ≥ 0", at.text)));
    }
    Ok(c)
}

/// Per-vertex data as the dialect gives it: `vt` belongs to the most recent `v`.
struct Vertex {
    position: Vec3,
    tex_coord: Option<Vec2>,
}

pub fn parse(path: &Path, text: &str) -> Result<Scene, SceneError> {
    let mut p = Parser {
        file: path.to_path_buf(),
        lexer: Lexer::new(text),
        peeked: None,
        last: (1, 1),
    };
    let mut scene = Scene {
        path: path.to_path_buf(),
        background: Vec3::ONE,
        ..Scene::default()
    };
    let mut vertices: Vec<Vertex> = Vec::new();
    // The selected material and the token that selected it (checked at the end of the file,
    // so that a file may define materials after selecting them).
    let mut current: Option<(u32, Token)> = None;
    let mut selections: Vec<(u32, Token)> = Vec::new();
    // `fog K` and where it was given (checked at the end, as material selections are).
    let mut fog: Option<(i64, Token)> = None;
    // The line of the sky given, and `sky_scale` (applied at the end, wherever it stands).
    let mut sky_at: Option<u32> = None;
    let mut sky_scale = 1.0;
    // (material, medium K, where) of each `interior_medium K`, checked once the media are known.
    let mut interiors = Vec::new();

    while let Some(tok) = p.next() {
        match tok.text {
            "material" => {
                let mut m = Material {
                    line: tok.line,
                    ..Material::default()
                };
                let mut has_albedo = false;
                let mut patterns = PatternKeys::default();
                while let Some(key) = p.peek().filter(|k| MATERIAL_KEYS.contains(&k.text)) {
                    p.next();
                    if key.text.starts_with("texture_") && key.text != "texture_file"
                        || key.text.starts_with("bump_")
                    {
                        patterns.read(&mut p, key)?;
                        has_albedo |= key.text == "texture_procedural";
                        continue;
                    }
                    match key.text {
                        "diffuse" => {
                            m.diffuse = p.vec3("a real number (diffuse r g b)")?;
                            has_albedo = true;
                        }
                        "texture_file" => {
                            let name = p.next().ok_or_else(|| p.syntax(None, "a file name"))?;
                            m.texture_file = Some(PathBuf::from(name.text));
                            has_albedo = true;
                        }
                        "reflective" => m.reflective = p.vec3("a real number (reflective r g b)")?,
                        "emitted" => {
                            m.emitted = p.vec3("a real number (emitted r g b)")?;
                            if m.emitted.x < 0.0 || m.emitted.y < 0.0 || m.emitted.z < 0.0 {
                                return Err(p.invalid(key, "emitted radiance must be ≥ 0".into()));
                            }
                        }
                        "transmitted" => {
                            m.transmitted = p.vec3("a real number (transmitted r g b)")?
                        }
                        "ior" => {
                            m.ior = p.real("a real number (ior n)")?;
                            if m.ior <= 0.0 {
                                return Err(p.invalid(key, "ior must be > 0".into()));
                            }
                        }
                        "interior_medium" => {
                            let (k, at) = p.index("a medium index (interior_medium K)")?;
                            interiors.push((scene.materials.len(), k, at));
                        }
                        _ => m.roughness = p.real("a real number (roughness a)")?.clamp(0.0, 1.0),
                    }
                }
                if !has_albedo {
                    return Err(p.invalid(
                        tok,
                        "material has neither `diffuse` nor `texture_file` nor `texture_procedural`"
                            .into(),
                    ));
                }
                patterns.apply(&p, &mut m)?;
                scene.materials.push(m);
            }
            "m" => {
                let (k, at) = p.index("a material index (m K)")?;
                if k < 0 || k > u32::MAX as i64 {
                    return Err(p.invalid(at, format!("no material {k}")));
                }
                current = Some((k as u32, at));
                selections.push((k as u32, at));
            }
            "v" => {
                let position = p.vec3("a real number (v x y z)")?;
                vertices.push(Vertex {
                    position,
                    tex_coord: None,
                });
            }
            "vt" => {
                let st = vec2(p.real("a real number (vt s t)")?, p.real("a real number (vt s t)")?);
                match vertices.last_mut() {
                    Some(v) => v.tex_coord = Some(st),
                    None => return Err(p.invalid(tok, "`vt` before any `v`".into())),
                }
            }
            "f" => {
                let material = material_for(&p, tok, current)?;
                let mut idx = [0usize; 4];
                for slot in &mut idx {
                    let (k, at) = p.index("a vertex index (f a b c d)")?;
                    if k < 1 || k as usize > vertices.len() {
                        return Err(p.invalid(
                            at,
                            format!(
                                "face index {k} out of range: {} vertices defined so far",
                                vertices.len()
                            ),
                        ));
                    }
                    *slot = k as usize - 1;
                }
                let vs = idx.map(|k| vertices[k].position);
                check_quad(&p, tok, &vs)?;
                let tex_coords = if idx.iter().all(|&k| vertices[k].tex_coord.is_some()) {
                    Some(idx.map(|k| vertices[k].tex_coord.unwrap_or_default()))
                } else {
                    None
                };
                scene.quads.push(Quad::new(vs, tex_coords, material));
            }
            "s" => {
                let material = material_for(&p, tok, current)?;
                let centre = p.vec3("a real number (s x y z r)")?;
                let radius = p.real("a real number (s x y z r)")?;
                if radius <= 0.0 {
                    return Err(p.invalid(tok, format!("sphere radius must be > 0, found {radius}")));
                }
                scene.shapes.push(ShapePrim {
                    shape: SphereShape { centre, radius }.into(),
                    material,
                });
            }
            "r" => {
                let material = material_for(&p, tok, current)?;
                let what = "a real number (r x y z h r_in r_out)";
                let base = p.vec3(what)?;
                let (height, r_in, r_out) = (p.real(what)?, p.real(what)?, p.real(what)?);
                if height <= 0.0 {
                    return Err(p.invalid(tok, format!("ring height must be > 0, found {height}")));
                }
                if !(r_in > 0.0 && r_in < r_out) {
                    return Err(p.invalid(
                        tok,
                        format!("ring radii must satisfy 0 < r_in < r_out, found r_in {r_in}, r_out {r_out}"),
                    ));
                }
                scene.shapes.push(ShapePrim {
                    shape: RingShape {
                        base,
                        height,
                        r_in,
                        r_out,
                    }
                    .into(),
                    material,
                });
            }
            "medium" => {
                let mut m = Medium {
                    line: tok.line,
                    ..Medium::default()
                };
                while let Some(key) = p.peek().filter(|k| MEDIUM_KEYS.contains(&k.text)) {
                    p.next();
                    match key.text {
                        "sigma_a" | "sigma_s" => {
                            let what = format!("a real number ({} r g b)", key.text);
                            let c = p.vec3(&what)?;
                            if c.min_element() < 0.0 {
                                return Err(p.invalid(key, format!("{} must be ≥ 0", key.text)));
                            }
                            *(if key.text == "sigma_a" { &mut m.sigma_a } else { &mut m.sigma_s }) = c;
                        }
                        _ => {
                            m.g = p.real("a real number (g asymmetry)")?;
                            if m.g.abs() >= 1.0 {
                                return Err(p.invalid(
                                    key,
                                    "the Henyey–Greenstein asymmetry g must lie in (−1, 1)".into(),
                                ));
                            }
                        }
                    }
                }
                scene.media.push(m);
            }
            "sky_color" | "sky_gradient" | "sky_texture" => {
                if let Some(first) = sky_at {
                    return Err(p.invalid(
                        tok,
                        format!(
                            "a second sky (the first at line {first}): give at most one of sky_color, sky_gradient, sky_texture"
                        ),
                    ));
                }
                sky_at = Some(tok.line);
                scene.sky = Some(match tok.text {
                    "sky_color" => {
                        let c = p.vec3("a real number (sky_color r g b)")?;
                        Sky::Uniform(non_negative(&p, tok, c)?)
                    }
                    "sky_gradient" => {
                        let what = "a real number (sky_gradient zenith horizon nadir, 3 × r g b)";
                        let (zenith, horizon, nadir) = (p.vec3(what)?, p.vec3(what)?, p.vec3(what)?);
                        Sky::Gradient {
                            zenith: non_negative(&p, tok, zenith)?,
                            horizon: non_negative(&p, tok, horizon)?,
                            nadir: non_negative(&p, tok, nadir)?,
                        }
                    }
                    _ => {
                        let name = p
                            .next()
                            .ok_or_else(|| p.syntax(None, "a file name (sky_texture f)"))?;
                        Sky::Map(Arc::new(SkyMap::named(PathBuf::from(name.text), tok.line)))
                    }
                });
            }
            "sky_scale" => {
                let scale = p.real("a real number (sky_scale s)")?;
                if scale < 0.0 {
                    return Err(p.invalid(tok, "sky_scale must be ≥ 0".into()));
                }
                sky_scale = scale;
            }
            "fog" => {
                let (k, at) = p.index("a medium index (fog K)")?;
                fog = Some((k, at));
            }
            "background_color" => {
                let c = p.vec3("a real number (background_color r g b)")?;
                scene.background = vec3(srgb_to_linear(c.x), srgb_to_linear(c.y), srgb_to_linear(c.z));
            }
            "PerspectiveCamera" | "OrthographicCamera" => {
                scene.camera = Some(parse_camera(&mut p, tok)?);
            }
            _ => {
                return Err(p.syntax(
                    Some(tok),
                    "a scene token (material, m, v, vt, f, s, r, medium, fog, sky_color, sky_gradient, sky_texture, sky_scale, background_color, PerspectiveCamera, OrthographicCamera)",
                ))
            }
        }
    }

    scene.sky = scene.sky.map(|sky| sky.scaled(sky_scale));
    // A medium index given by `key` must name one of the file's medium blocks.
    let count = scene.media.len();
    let medium = |key: &str, k: i64, at: Token| -> Result<usize, SceneError> {
        if k < 0 || k as usize >= count {
            return Err(p.invalid(
                at,
                format!(
                    "{key} {k}: no such medium (the file defines {count} medium block{})",
                    if count == 1 { "" } else { "s" }
                ),
            ));
        }
        Ok(k as usize)
    };
    if let Some((k, at)) = fog {
        scene.fog = Some(medium("fog", k, at)?);
    }
    for (material, k, at) in interiors {
        let k = medium("interior_medium", k, at)?;
        let m = &mut scene.materials[material];
        // Only a refracting boundary delimits a medium so far: an index-matched one (no
        // `transmitted`) would have to let shadow rays through, which the Accel's occlusion
        // queries do not know of.
        if m.transmitted.max_element() <= 0.0 {
            return Err(p.invalid(
                at,
                "interior_medium needs `transmitted` in its material (a refracting boundary); index-matched boundaries are not read yet".into(),
            ));
        }
        m.interior_medium = Some(k);
    }
    for (k, at) in selections {
        if k as usize >= scene.materials.len() {
            return Err(p.invalid(
                at,
                format!(
                    "m {k}: no such material ({} defined)",
                    scene.materials.len()
                ),
            ));
        }
    }
    Ok(scene)
}

fn material_for(p: &Parser, tok: Token, current: Option<(u32, Token)>) -> Result<u32, SceneError> {
    current.map(|(k, _)| k).ok_or_else(|| {
        p.invalid(
            tok,
            format!("`{}` before any `m` selects a material", tok.text),
        )
    })
}

/// Rejects zero-area and non-planar quads; nearly degenerate ones are kept.
fn check_quad(p: &Parser, tok: Token, v: &[Vec3; 4]) -> Result<(), SceneError> {
    let n = quad_normal(v);
    let size = (v[2] - v[0]).length().max((v[3] - v[1]).length());
    let area2 = n.length();
    if area2.is_nan() || area2 <= f32::EPSILON * f32::EPSILON * size * size {
        return Err(p.invalid(tok, "degenerate quad: its area is zero".into()));
    }
    let unit = n * area2.recip();
    if let Some(off_plane) = quad_off_plane(v, unit, size) {
        return Err(p.invalid(
            tok,
            format!("non-planar quad: a vertex lies {off_plane} off the quad's plane"),
        ));
    }
    Ok(())
}

fn parse_camera(p: &mut Parser, tok: Token) -> Result<Camera, SceneError> {
    p.expect("{")?;
    let perspective = tok.text == "PerspectiveCamera";
    let (mut position, mut poi, mut up) = (None, None, None);
    let mut param = None;
    loop {
        let key = p.next();
        match key.map(|k| k.text) {
            Some("}") => break,
            Some("camera_position") => position = Some(p.vec3("a real number")?),
            Some("point_of_interest") => poi = Some(p.vec3("a real number")?),
            Some("up") => up = Some(p.vec3("a real number")?),
            Some("angle") if perspective => param = Some(p.real("a real number (angle)")?),
            Some("size") if !perspective => param = Some(p.real("a real number (size)")?),
            _ => {
                let keys = if perspective {
                    "camera_position, point_of_interest, up, angle or `}`"
                } else {
                    "camera_position, point_of_interest, up, size or `}`"
                };
                return Err(p.syntax(key, keys));
            }
        }
    }
    let missing = |what: &str| p.invalid(tok, format!("{} has no `{what}`", tok.text));
    let position = position.ok_or_else(|| missing("camera_position"))?;
    let poi = poi.ok_or_else(|| missing("point_of_interest"))?;
    let up = up.ok_or_else(|| missing("up"))?;
    let param = param.ok_or_else(|| missing(if perspective { "angle" } else { "size" }))?;
    if (poi - position).length_squared() == 0.0
        || (poi - position).cross(up).length_squared() == 0.0
    {
        return Err(p.invalid(
            tok,
            "camera looks at its own position or along its up vector".into(),
        ));
    }
    let projection = if perspective {
        if !(param > 0.0 && param < std::f32::consts::PI) {
            return Err(p.invalid(tok, format!("angle must be in (0, π), found {param}")));
        }
        Projection::Perspective { angle: param }
    } else {
        if param <= 0.0 {
            return Err(p.invalid(tok, format!("size must be > 0, found {param}")));
        }
        Projection::Orthographic { size: param }
    };
    Ok(Camera {
        position,
        point_of_interest: poi,
        up,
        projection,
    })
}
