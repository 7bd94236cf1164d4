//! Mitsuba 3's XML, read into a tree of plugins: `<default>` and `$name` substitution (with
//! the command line's `--define`), `<include>` (cycles refused), `<path>`, `id` and `<ref>`,
//! nested plugins, and typed properties (`float`, `integer`, `boolean`, `string`, `rgb`,
//! `spectrum`, `point`, `vector`, `transform`). What the plugins mean is `super`'s business.

use std::cell::Cell;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::rc::Rc;

use glam::{DMat4, DVec3};

use super::spectrum::Spectrum;
use crate::scene::range::{in_range, RANGE};
use crate::scene::SceneError;

/// The largest file `<include>` or the scene itself may be: a scene description, not a mesh.
const MAX_XML_BYTES: u64 = 64 << 20;
/// Includes nested deeper than this are refused (a cycle is found sooner, by name).
const MAX_INCLUDE_DEPTH: usize = 64;

/// Where something is written: file, line and column (1-based).
#[derive(Clone, Debug, PartialEq)]
pub struct Location {
    pub file: Rc<PathBuf>,
    pub line: u32,
    pub column: u32,
}

impl Location {
    /// An error at this place.
    pub fn error(&self, message: impl Into<String>) -> SceneError {
        SceneError::Invalid {
            file: self.file.to_path_buf(),
            line: self.line,
            column: self.column,
            message: message.into(),
        }
    }
}

impl std::fmt::Display for Location {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{}:{}", self.file.display(), self.line, self.column)
    }
}

/// A property's value.
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    Float(f64),
    Integer(i64),
    Boolean(bool),
    String(String),
    Rgb(DVec3),
    Spectrum(Spectrum),
    Point(DVec3),
    Vector(DVec3),
    Transform(DMat4),
}

impl Value {
    fn kind(&self) -> &'static str {
        match self {
            Value::Float(_) => "float",
            Value::Integer(_) => "integer",
            Value::Boolean(_) => "boolean",
            Value::String(_) => "string",
            Value::Rgb(_) => "rgb",
            Value::Spectrum(_) => "spectrum",
            Value::Point(_) => "point",
            Value::Vector(_) => "vector",
            Value::Transform(_) => "transform",
        }
    }
}

/// A named property of a plugin, and whether the reader has used it.
#[derive(Debug)]
pub struct Property {
    pub name: String,
    pub value: Value,
    pub at: Location,
    /// The `<path>` folders in force where the property was written (a file it names is
    /// looked for there, newest first, then beside the scene file that names it).
    search: Rc<Vec<PathBuf>>,
    used: Cell<bool>,
}

/// A plugin: `<shape type="obj">`, `<bsdf type="diffuse">`, …, with its properties and the
/// plugins nested in it (or referenced from it).
#[derive(Debug)]
pub struct Plugin {
    /// The element: `scene`, `shape`, `bsdf`, `emitter`, `sensor`, `film`, `sampler`,
    /// `integrator`, `texture`, `medium`, `phase`, `rfilter`, `volume`, `spectrum`.
    pub tag: String,
    /// Its `type` attribute.
    pub kind: String,
    /// The `name` it is nested under (`<texture name="reflectance">`, `<ref name="interior">`).
    pub name: Option<String>,
    /// Its `id` attribute, which `<ref>` names it by.
    pub id: Option<String>,
    pub properties: Vec<Property>,
    pub children: Vec<Child>,
    pub at: Location,
    used: Cell<bool>,
}

/// A nested plugin: its own, or one referenced by id, under the name it is given here.
#[derive(Clone, Debug)]
pub struct Child {
    pub name: Option<String>,
    pub plugin: Rc<Plugin>,
}

impl Plugin {
    /// The property `name`, marked as used.
    pub fn property(&self, name: &str) -> Option<&Property> {
        let p = self.properties.iter().rev().find(|p| p.name == name)?;
        p.used.set(true);
        Some(p)
    }

    /// The children with this tag, in order.
    pub fn children_tagged<'a>(&'a self, tag: &'a str) -> impl Iterator<Item = &'a Child> + 'a {
        self.children.iter().filter(move |c| c.plugin.tag == tag)
    }

    /// The child plugin nested under `name`.
    pub fn child_named(&self, name: &str) -> Option<&Rc<Plugin>> {
        self.children
            .iter()
            .find(|c| c.name.as_deref() == Some(name))
            .map(|c| &c.plugin)
    }

    /// Marks the plugin as read (its properties are checked for use by `unused`).
    pub fn mark_used(&self) {
        self.used.set(true);
    }

    /// A float property (an integer is taken as a float too), or `default`.
    pub fn float(&self, name: &str, default: f64) -> Result<f64, SceneError> {
        match self.property(name) {
            None => Ok(default),
            Some(p) => match p.value {
                Value::Float(v) => Ok(v),
                Value::Integer(v) => Ok(v as f64),
                _ => Err(wrong_kind(p, "float")),
            },
        }
    }

    /// An integer property, or `default`.
    pub fn integer(&self, name: &str, default: i64) -> Result<i64, SceneError> {
        match self.property(name) {
            None => Ok(default),
            Some(p) => match p.value {
                Value::Integer(v) => Ok(v),
                _ => Err(wrong_kind(p, "integer")),
            },
        }
    }

    /// A boolean property, or `default`.
    pub fn boolean(&self, name: &str, default: bool) -> Result<bool, SceneError> {
        match self.property(name) {
            None => Ok(default),
            Some(p) => match p.value {
                Value::Boolean(v) => Ok(v),
                _ => Err(wrong_kind(p, "boolean")),
            },
        }
    }

    /// A string property.
    pub fn string(&self, name: &str) -> Result<Option<(&str, &Location)>, SceneError> {
        match self.property(name) {
            None => Ok(None),
            Some(p) => match &p.value {
                Value::String(s) => Ok(Some((s, &p.at))),
                _ => Err(wrong_kind(p, "string")),
            },
        }
    }

    /// A string property naming a file, resolved through the `<path>` folders and made
    /// absolute (textures are read relative to the scene, where an absolute path stays
    /// itself).
    pub fn file(&self, name: &str) -> Result<Option<(PathBuf, &Location)>, SceneError> {
        let Some(p) = self.property(name) else {
            return Ok(None);
        };
        let Value::String(s) = &p.value else {
            return Err(wrong_kind(p, "string"));
        };
        let path = resolve(s, &p.search, &p.at.file);
        Ok(Some((std::path::absolute(&path).unwrap_or(path), &p.at)))
    }

    /// A transform property, or the identity.
    pub fn transform(&self, name: &str) -> Result<DMat4, SceneError> {
        match self.property(name) {
            None => Ok(DMat4::IDENTITY),
            Some(p) => match p.value {
                Value::Transform(m) => Ok(m),
                _ => Err(wrong_kind(p, "transform")),
            },
        }
    }

    /// A point property, or `default`.
    pub fn point(&self, name: &str, default: DVec3) -> Result<DVec3, SceneError> {
        match self.property(name) {
            None => Ok(default),
            Some(p) => match p.value {
                Value::Point(v) | Value::Vector(v) => Ok(v),
                _ => Err(wrong_kind(p, "point")),
            },
        }
    }

    /// Every property and plugin of this tree that the reader did not read, as warnings: a
    /// parameter trilux does not know is named, not silently ignored.
    pub fn unused(&self, out: &mut Vec<String>) {
        if !self.used.get() {
            out.push(format!(
                "{}: <{} type=\"{}\"> is not used by trilux",
                self.at, self.tag, self.kind
            ));
            return;
        }
        for p in &self.properties {
            if !p.used.get() {
                out.push(format!(
                    "{}: parameter \"{}\" of <{} type=\"{}\"> is not used by trilux",
                    p.at, p.name, self.tag, self.kind
                ));
            }
        }
        // A plugin referenced from several places is reported from each (the caller keeps
        // one of equal lines).
        for c in &self.children {
            c.plugin.unused(out);
        }
    }
}

fn wrong_kind(p: &Property, expected: &str) -> SceneError {
    p.at.error(format!(
        "parameter \"{}\" is a {}, expected a {expected}",
        p.name,
        p.value.kind()
    ))
}

/// The plugin elements (everything else is a property or a directive).
const PLUGIN_TAGS: [&str; 14] = [
    "scene",
    "shape",
    "bsdf",
    "emitter",
    "sensor",
    "film",
    "sampler",
    "integrator",
    "texture",
    "medium",
    "phase",
    "rfilter",
    "volume",
    "spectrum",
];

/// Reads the scene file `path` with the `--define`d parameters (which win over its
/// `<default>`s) into its root `<scene>` plugin.
pub fn read(path: &Path, defines: &[(String, String)]) -> Result<Rc<Plugin>, SceneError> {
    let mut reader = Reader {
        parameters: defines.iter().cloned().collect(),
        defined: defines.iter().map(|(k, _)| k.clone()).collect(),
        ids: HashMap::new(),
        // Files are found as Mitsuba's file resolver finds them: in the `<path>` folders,
        // then in the main scene file's folder (also for what an included file names).
        search: Rc::new(vec![path.parent().unwrap_or(Path::new("")).to_path_buf()]),
        including: Vec::new(),
    };
    let root = reader.file(
        path,
        &Location {
            file: Rc::new(path.to_path_buf()),
            line: 0,
            column: 0,
        },
    )?;
    Ok(Rc::new(root))
}

struct Reader {
    /// `$name` → value: `<default>`s and `--define`s.
    parameters: HashMap<String, String>,
    /// Names given by `--define`, which `<default>` does not override.
    defined: Vec<String>,
    /// Plugins by `id`, for `<ref>`.
    ids: HashMap<String, Rc<Plugin>>,
    /// Folders `<path>` added, searched (newest first) before the including file's folder.
    search: Rc<Vec<PathBuf>>,
    /// The files being read, outermost first (an include of one of them is a cycle).
    including: Vec<PathBuf>,
}

impl Reader {
    /// Reads one file whose root element is `<scene>`; `from` is where it was named.
    fn file(&mut self, path: &Path, from: &Location) -> Result<Plugin, SceneError> {
        let canonical = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
        if self.including.contains(&canonical) {
            return Err(from.error(format!(
                "<include> of {} makes a cycle: it is already being read",
                path.display()
            )));
        }
        if self.including.len() >= MAX_INCLUDE_DEPTH {
            return Err(from.error(format!(
                "includes nested more than {MAX_INCLUDE_DEPTH} deep"
            )));
        }
        let io = |source| SceneError::Io {
            file: path.to_path_buf(),
            source,
        };
        let size = std::fs::metadata(path).map_err(io)?.len();
        if size > MAX_XML_BYTES {
            return Err(SceneError::Obj {
                file: path.to_path_buf(),
                message: format!(
                    "{size} bytes: larger than a scene description may be ({MAX_XML_BYTES})"
                ),
            });
        }
        let text = std::fs::read_to_string(path).map_err(io)?;
        let file = Rc::new(path.to_path_buf());
        let doc = roxmltree::Document::parse(&text).map_err(|e| {
            let pos = e.pos();
            SceneError::Invalid {
                file: path.to_path_buf(),
                line: pos.row,
                column: pos.col,
                message: format!("malformed XML: {e}"),
            }
        })?;
        let root = doc.root_element();
        let lines = Lines::new(&text);
        let at = location(&lines, root, &file);
        if root.tag_name().name() != "scene" {
            return Err(at.error(format!(
                "the root element is <{}>, expected <scene>",
                root.tag_name().name()
            )));
        }
        self.including.push(canonical);
        let mut scene = Plugin {
            tag: "scene".into(),
            kind: String::new(),
            name: None,
            id: None,
            properties: Vec::new(),
            children: Vec::new(),
            at,
            used: Cell::new(true),
        };
        let result = self.contents(&lines, root, &file, &mut scene);
        self.including.pop();
        result?;
        Ok(scene)
    }

    /// The elements inside `node`, added to `parent`.
    fn contents(
        &mut self,
        lines: &Lines,
        node: roxmltree::Node,
        file: &Rc<PathBuf>,
        parent: &mut Plugin,
    ) -> Result<(), SceneError> {
        for child in node.children().filter(|n| n.is_element()) {
            self.element(lines, child, file, parent)?;
        }
        Ok(())
    }

    fn property(&self, name: String, value: Value, at: Location) -> Property {
        Property {
            name,
            value,
            at,
            search: self.search.clone(),
            used: Cell::new(false),
        }
    }

    /// An attribute with `$name`s substituted; None when absent.
    fn attribute(
        &self,
        node: roxmltree::Node,
        name: &str,
        at: &Location,
    ) -> Result<Option<String>, SceneError> {
        let Some(raw) = node.attribute(name) else {
            return Ok(None);
        };
        let mut out = String::with_capacity(raw.len());
        let mut rest = raw;
        while let Some(k) = rest.find('$') {
            out.push_str(&rest[..k]);
            let after = &rest[k + 1..];
            let len = after
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                .unwrap_or(after.len());
            let key = &after[..len];
            match self.parameters.get(key) {
                Some(v) if !key.is_empty() => out.push_str(v),
                _ => {
                    return Err(at.error(format!(
                        "attribute {name}=\"{raw}\": ${key} is not defined (give it a <default> or --define {key}=VALUE)"
                    )))
                }
            }
            rest = &after[len..];
        }
        out.push_str(rest);
        Ok(Some(out))
    }

    fn required(
        &self,
        node: roxmltree::Node,
        name: &str,
        at: &Location,
    ) -> Result<String, SceneError> {
        self.attribute(node, name, at)?.ok_or_else(|| {
            at.error(format!(
                "<{}> needs a \"{name}\" attribute",
                node.tag_name().name()
            ))
        })
    }

    fn element(
        &mut self,
        lines: &Lines,
        node: roxmltree::Node,
        file: &Rc<PathBuf>,
        parent: &mut Plugin,
    ) -> Result<(), SceneError> {
        let at = location(lines, node, file);
        let tag = node.tag_name().name();
        match tag {
            "default" => {
                let name = self.required(node, "name", &at)?;
                let value = self.required(node, "value", &at)?;
                if !self.defined.contains(&name) {
                    self.parameters.insert(name, value);
                }
            }
            "path" => {
                let value = self.required(node, "value", &at)?;
                let dir = file.parent().unwrap_or(Path::new("")).join(value);
                Rc::make_mut(&mut self.search).push(dir);
            }
            "include" => {
                let name = self.required(node, "filename", &at)?;
                let path = resolve(&name, &self.search, file);
                let included = self.file(&path, &at)?;
                parent.properties.extend(included.properties);
                parent.children.extend(included.children);
            }
            "ref" => {
                let id = self.required(node, "id", &at)?;
                let plugin = self.ids.get(&id).cloned().ok_or_else(|| {
                    at.error(format!("<ref id=\"{id}\">: no plugin has this id (ids are defined before they are referenced)"))
                })?;
                parent.children.push(Child {
                    name: self.attribute(node, "name", &at)?,
                    plugin,
                });
            }
            "transform" => {
                let name = self.required(node, "name", &at)?;
                let mut m = DMat4::IDENTITY;
                for op in node.children().filter(|n| n.is_element()) {
                    let op_at = location(lines, op, file);
                    m = self.transform_op(op, &op_at)? * m;
                }
                parent
                    .properties
                    .push(self.property(name, Value::Transform(m), at));
            }
            "spectrum" if node.attribute("type").is_none() => {
                let name = self.required(node, "name", &at)?;
                let spectrum = if let Some(v) = self.attribute(node, "value", &at)? {
                    parse_spectrum(&v, &at)?
                } else if let Some(f) = self.attribute(node, "filename", &at)? {
                    read_spd(&resolve(&f, &self.search, file), &at)?
                } else {
                    return Err(at.error("<spectrum> needs a \"value\" or a \"filename\""));
                };
                parent
                    .properties
                    .push(self.property(name, Value::Spectrum(spectrum), at));
            }
            "float" | "integer" | "boolean" | "string" | "rgb" | "point" | "vector" => {
                let name = self.required(node, "name", &at)?;
                let value = match tag {
                    "point" | "vector" => {
                        let v = self.vector(node, &at, 0.0)?;
                        if let Some(bad) = v.to_array().into_iter().find(|c| !in_range(*c as f32)) {
                            return Err(at.error(format!("a coordinate of {bad}: {RANGE}")));
                        }
                        if tag == "point" {
                            Value::Point(v)
                        } else {
                            Value::Vector(v)
                        }
                    }
                    _ => {
                        let text = self.required(node, "value", &at)?;
                        parse_value(tag, &text, &at)?
                    }
                };
                parent.properties.push(self.property(name, value, at));
            }
            t if PLUGIN_TAGS.contains(&t) && t != "scene" => {
                let kind = self.attribute(node, "type", &at)?.unwrap_or_default();
                let id = self.attribute(node, "id", &at)?;
                let mut plugin = Plugin {
                    tag: t.into(),
                    kind,
                    name: self.attribute(node, "name", &at)?,
                    id: id.clone(),
                    properties: Vec::new(),
                    children: Vec::new(),
                    at,
                    used: Cell::new(false),
                };
                self.contents(lines, node, file, &mut plugin)?;
                let plugin = Rc::new(plugin);
                if let Some(id) = id {
                    if let Some(first) = self.ids.get(&id) {
                        return Err(plugin.at.error(format!(
                            "id \"{id}\" is given twice (first at {})",
                            first.at
                        )));
                    }
                    self.ids.insert(id, plugin.clone());
                }
                parent.children.push(Child {
                    name: plugin.name.clone(),
                    plugin,
                });
            }
            other => {
                return Err(at.error(format!(
                    "unknown element <{other}>: expected a plugin ({}), a property (float, integer, boolean, string, rgb, spectrum, point, vector, transform), or default, include, path, ref",
                    PLUGIN_TAGS.join(", ")
                )))
            }
        }
        Ok(())
    }

    /// A vector written as `x`, `y`, `z` attributes (each `default` when absent) or as
    /// `value="x, y, z"` (one number for all three).
    fn vector(
        &self,
        node: roxmltree::Node,
        at: &Location,
        default: f64,
    ) -> Result<DVec3, SceneError> {
        if let Some(v) = self.attribute(node, "value", at)? {
            let n = numbers(&v, at)?;
            return match n[..] {
                [a] => Ok(DVec3::splat(a)),
                [x, y, z] => Ok(DVec3::new(x, y, z)),
                _ => Err(at.error(format!("value=\"{v}\": expected one or three numbers"))),
            };
        }
        let mut out = [default; 3];
        for (k, axis) in ["x", "y", "z"].iter().enumerate() {
            if let Some(v) = self.attribute(node, axis, at)? {
                out[k] = number(&v, at)?;
            }
        }
        Ok(DVec3::from_array(out))
    }

    /// One operation of a `<transform>`, as a matrix applied after the ones before it.
    fn transform_op(&self, op: roxmltree::Node, at: &Location) -> Result<DMat4, SceneError> {
        let m = match op.tag_name().name() {
            "translate" => DMat4::from_translation(self.vector(op, at, 0.0)?),
            "scale" => DMat4::from_scale(self.vector(op, at, 1.0)?),
            "rotate" => {
                let axis = self.vector(op, at, 0.0)?;
                let angle = number(&self.required(op, "angle", at)?, at)?;
                if axis.length_squared() == 0.0 {
                    return Err(at.error("<rotate>: the axis is zero"));
                }
                DMat4::from_axis_angle(axis.normalize(), angle.to_radians())
            }
            "matrix" => {
                let v = self.required(op, "value", at)?;
                let n = numbers(&v, at)?;
                match n.len() {
                    // Row-major, as written.
                    16 => DMat4::from_cols_array(&n.try_into().unwrap_or([0.0; 16])).transpose(),
                    9 => {
                        let r = |i: usize| DVec3::new(n[3 * i], n[3 * i + 1], n[3 * i + 2]);
                        DMat4::from_mat3(glam::DMat3::from_cols(r(0), r(1), r(2)).transpose())
                    }
                    k => {
                        return Err(at.error(format!(
                            "<matrix> has {k} numbers, expected 16 (or 9), row by row"
                        )))
                    }
                }
            }
            "lookat" => {
                let point = |name: &str| -> Result<DVec3, SceneError> {
                    let v = self.required(op, name, at)?;
                    let n = numbers(&v, at)?;
                    match n[..] {
                        [x, y, z] => Ok(DVec3::new(x, y, z)),
                        _ => Err(at.error(format!("{name}=\"{v}\": expected three numbers"))),
                    }
                };
                let origin = point("origin")?;
                let target = point("target")?;
                let up = match self.attribute(op, "up", at)? {
                    Some(_) => point("up")?,
                    None => DVec3::Y,
                };
                look_at(origin, target, up).ok_or_else(|| {
                    at.error("<lookat>: origin and target coincide, or up is along the view")
                })?
            }
            other => {
                return Err(at.error(format!(
                "unknown transform <{other}>: expected translate, rotate, scale, matrix or lookat"
            )))
            }
        };
        if let Some(bad) = m.to_cols_array().into_iter().find(|v| !in_range(*v as f32)) {
            return Err(at.error(format!("a transform entry of {bad}: {RANGE}")));
        }
        Ok(m)
    }
}

/// Mitsuba's look-at: the camera's +z towards the target, +y towards `up`, +x to its left.
fn look_at(origin: DVec3, target: DVec3, up: DVec3) -> Option<DMat4> {
    let dir = (target - origin).try_normalize()?;
    let left = up.cross(dir).try_normalize()?;
    let new_up = dir.cross(left);
    Some(DMat4::from_cols(
        left.extend(0.0),
        new_up.extend(0.0),
        dir.extend(0.0),
        origin.extend(1.0),
    ))
}

/// A file named by the scene: as given if absolute, else in the folders `search` (the
/// `<path>`s newest first, the main scene's folder last), then beside `file`, the scene file
/// that names it.
fn resolve(name: &str, search: &[PathBuf], file: &Path) -> PathBuf {
    let p = Path::new(name);
    if p.is_absolute() {
        return p.to_path_buf();
    }
    let beside = file.parent().unwrap_or(Path::new("")).join(p);
    search
        .iter()
        .rev()
        .map(|dir| dir.join(p))
        .find(|c| c.exists())
        .unwrap_or(beside)
}

fn location(lines: &Lines, node: roxmltree::Node, file: &Rc<PathBuf>) -> Location {
    let (line, column) = lines.at(node.range().start);
    Location {
        file: file.clone(),
        line,
        column,
    }
}

/// Where each line of a file's text starts, so that an element's line and column are a binary
/// search away. roxmltree's `text_pos_at` counts them from the start of the text, which made
/// reading a scene quadratic in its length: 4.5 s for a file of 10,000 `<shape>`s.
struct Lines<'t> {
    text: &'t str,
    /// The byte offset of each line's first character: 0, then one past each newline.
    starts: Vec<usize>,
}

impl<'t> Lines<'t> {
    fn new(text: &'t str) -> Lines<'t> {
        let starts = std::iter::once(0)
            .chain(text.match_indices('\n').map(|(k, _)| k + 1))
            .collect();
        Lines { text, starts }
    }

    /// The line and column (both from 1, the column in characters) of byte offset `pos`, as
    /// `roxmltree::Document::text_pos_at` gives them.
    fn at(&self, pos: usize) -> (u32, u32) {
        let pos = pos.min(self.text.len());
        let line = self.starts.partition_point(|&s| s <= pos);
        let start = self.starts[line - 1];
        let column = self.text[start..pos].chars().count() + 1;
        (line as u32, column as u32)
    }
}

fn number(text: &str, at: &Location) -> Result<f64, SceneError> {
    let t = text.trim();
    t.parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| at.error(format!("\"{t}\" is not a finite number")))
}

/// Numbers separated by commas and/or white space.
fn numbers(text: &str, at: &Location) -> Result<Vec<f64>, SceneError> {
    text.split(|c: char| c == ',' || c.is_whitespace())
        .filter(|w| !w.is_empty())
        .map(|w| number(w, at))
        .collect()
}

fn parse_value(tag: &str, text: &str, at: &Location) -> Result<Value, SceneError> {
    Ok(match tag {
        "float" => Value::Float(number(text, at)?),
        "integer" => Value::Integer(
            text.trim()
                .parse()
                .map_err(|_| at.error(format!("\"{text}\" is not an integer")))?,
        ),
        "boolean" => Value::Boolean(match text.trim() {
            "true" => true,
            "false" => false,
            _ => return Err(at.error(format!("\"{text}\" is not true or false"))),
        }),
        "string" => Value::String(text.to_string()),
        "rgb" => {
            let n = numbers(text, at)?;
            Value::Rgb(match n[..] {
                [v] => DVec3::splat(v),
                [r, g, b] => DVec3::new(r, g, b),
                _ => {
                    return Err(at.error(format!(
                        "rgb value=\"{text}\": expected one or three numbers"
                    )))
                }
            })
        }
        _ => unreachable!("parse_value is called for scalar tags only"),
    })
}

/// `value="0.5"` (uniform) or `value="400:0.1, 500:0.2, …"` (wavelength:value pairs).
fn parse_spectrum(text: &str, at: &Location) -> Result<Spectrum, SceneError> {
    if !text.contains(':') {
        let n = numbers(text, at)?;
        return match n[..] {
            [v] => Ok(Spectrum::Uniform(v)),
            _ => Err(at.error(format!(
                "spectrum value=\"{text}\": expected one number or wavelength:value pairs"
            ))),
        };
    }
    let pairs = text
        .split(',')
        .filter(|p| !p.trim().is_empty())
        .map(|p| {
            let (w, v) = p
                .split_once(':')
                .ok_or_else(|| at.error(format!("\"{p}\" is not a wavelength:value pair")))?;
            Ok((number(w, at)?, number(v, at)?))
        })
        .collect::<Result<Vec<_>, SceneError>>()?;
    spectrum_of_pairs(pairs, at)
}

fn spectrum_of_pairs(pairs: Vec<(f64, f64)>, at: &Location) -> Result<Spectrum, SceneError> {
    if pairs.is_empty() {
        return Err(at.error("the spectrum has no values"));
    }
    if pairs.windows(2).any(|w| w[1].0 <= w[0].0) {
        return Err(at.error("the spectrum's wavelengths must increase"));
    }
    Ok(Spectrum::Pairs(pairs))
}

/// A spectrum file: lines of "wavelength value", `#` comments.
fn read_spd(path: &Path, at: &Location) -> Result<Spectrum, SceneError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| at.error(format!("cannot read spectrum {}: {e}", path.display())))?;
    let mut pairs = Vec::new();
    for line in text.lines() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let n = numbers(line, at)?;
        match n[..] {
            [w, v] => pairs.push((w, v)),
            _ => {
                return Err(at.error(format!(
                    "{}: \"{line}\" is not a wavelength and a value",
                    path.display()
                )))
            }
        }
    }
    spectrum_of_pairs(pairs, at)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `Lines::at` gives roxmltree's own line and column at every character of a text with
    /// several lines, Windows line ends, characters of more than one byte and an empty line.
    #[test]
    fn lines_give_the_positions_roxmltree_gives() {
        let text =
            "<scene version='3.0.0'>\r\n  <!-- é, ∂, 𝔼 -->\n\n\t<shape type=\"obj\"/>\n</scene>\n";
        let doc = roxmltree::Document::parse(text).expect("parses");
        let lines = Lines::new(text);
        for (pos, _) in text.char_indices().chain([(text.len(), ' ')]) {
            let theirs = doc.text_pos_at(pos);
            assert_eq!(lines.at(pos), (theirs.row, theirs.col), "at byte {pos}");
        }
    }
}
