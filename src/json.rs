//! Closure descriptions in JSON (serde_json). The format, documented in the README:
//!
//! ```json
//! { "transport": "radiance",
//!   "lobes": [ { "type": "conductor", "weight": [1, 1, 1],
//!                "normal": [0, 0, 1], "tangent": [1, 0, 0],
//!                "roughness": 0.3, "fresnel": "artistic", "reflectivity": [0.9, 0.6, 0.3] } ] }
//! ```
//!
//! Every key other than `type`, `weight`, `normal` and `tangent` is a parameter of the
//! lobe type's schema: numbers for `float`, a number or `[r, g, b]` for `rgb`, a choice
//! name for `enum`. Errors name the offending key or value and list the valid choices;
//! names from the input are shown JSON-escaped ([`quoted`]), so control characters
//! never reach a log raw.
//!
//! Stricter than JSON itself: a key given twice in one object is an error (JSON leaves
//! it open, and taking one silently would hide a typo), and `"lobes"` must not be
//! empty. A leading UTF-8 byte order mark is skipped. A `tangent` of `[0, 0, 0]`
//! means "choose one", as an all-zero `glint_frame.tangent` does in the C API.

use crate::closure::{Closure, MAX_LOBES};
use crate::error::{Error, Status};
use crate::lobes::Transport;
use crate::materials::{Material, ShadingContext};
use crate::math::Rgb;
use crate::math::{Frame, Vec3};
use crate::params::{self, ParamKind, ParamSpec, Shape};
use crate::registry::Registry;
use serde::de::{self, Deserialize, Deserializer, MapAccess, SeqAccess, Visitor};
use serde_json::{Map, Number, Value};

const LOBE_KEYS: &[&str] = &["type", "weight", "normal", "tangent"];
const MATERIAL_KEY: &str = "material";
/// Keys of a material entry besides its parameters (a material document alone takes
/// only `material`).
const MATERIAL_ENTRY_KEYS: &[&str] = &[MATERIAL_KEY, "weight", "normal", "tangent"];
const TOP_KEYS: &[&str] = &["lobes", "transport"];

fn parse_error(message: String) -> Error {
    Error::new(Status::Parse, message)
}

/// `s` as a JSON string literal: quoted, with control characters escaped.
pub fn quoted(s: &str) -> String {
    Value::from(s).to_string()
}

/// A JSON value whose objects have distinct keys: serde_json's [`Value`] keeps the
/// last of duplicates, so this visitor builds one and rejects them.
struct Strict(Value);

impl<'de> Deserialize<'de> for Strict {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserializer.deserialize_any(StrictVisitor).map(Strict)
    }
}

struct StrictVisitor;

impl<'de> Visitor<'de> for StrictVisitor {
    type Value = Value;

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a JSON value")
    }
    fn visit_unit<E>(self) -> Result<Value, E> {
        Ok(Value::Null)
    }
    fn visit_bool<E>(self, v: bool) -> Result<Value, E> {
        Ok(Value::Bool(v))
    }
    fn visit_i64<E>(self, v: i64) -> Result<Value, E> {
        Ok(v.into())
    }
    fn visit_u64<E>(self, v: u64) -> Result<Value, E> {
        Ok(v.into())
    }
    fn visit_f64<E>(self, v: f64) -> Result<Value, E> {
        Ok(Number::from_f64(v).map_or(Value::Null, Value::Number))
    }
    fn visit_str<E>(self, v: &str) -> Result<Value, E> {
        Ok(v.into())
    }
    fn visit_string<E>(self, v: String) -> Result<Value, E> {
        Ok(v.into())
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Value, A::Error> {
        let mut items = Vec::new();
        while let Some(Strict(v)) = seq.next_element()? {
            items.push(v);
        }
        Ok(Value::Array(items))
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Value, A::Error> {
        let mut object = Map::new();
        while let Some(key) = map.next_key::<String>()? {
            if object.contains_key(&key) {
                return Err(de::Error::custom(format!("duplicate key {}", quoted(&key))));
            }
            let Strict(value) = map.next_value()?;
            object.insert(key, value);
        }
        Ok(Value::Object(object))
    }
}

/// The root object of a JSON document.
fn parse_root(text: &str, what: &str) -> Result<Map<String, Value>, Error> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let Strict(root) =
        serde_json::from_str(text).map_err(|e| parse_error(format!("malformed JSON: {e}")))?;
    match root {
        Value::Object(obj) => Ok(obj),
        _ => Err(parse_error(format!("{what} must be a JSON object"))),
    }
}

/// Build (and finish) a closure from its JSON description: a `"lobes"` array whose
/// entries are lobes or materials, or one material document. Materials do not emit
/// lobes below `prune` ([`Material`]).
pub fn closure_from_json(
    registry: &Registry,
    text: &str,
    wo: Option<Vec3<f32>>,
    prune: f32,
) -> Result<Closure, Error> {
    let obj = parse_root(
        text,
        "a closure description (with a \"lobes\" array, or a \"material\")",
    )?;
    if obj.contains_key(MATERIAL_KEY) {
        let mut closure = Closure::new(wo, Transport::Radiance);
        add_material(registry, &mut closure, &obj, None, prune)?;
        closure.finish()?;
        return Ok(closure);
    }
    if let Some(key) = obj.keys().find(|k| !TOP_KEYS.contains(&k.as_str())) {
        return Err(Error::new(
            Status::UnknownName,
            format!(
                "unknown key {} in the closure; valid keys: {}",
                quoted(key),
                TOP_KEYS.join(", ")
            ),
        ));
    }
    let mode = match obj.get("transport") {
        None => Transport::Radiance,
        Some(Value::String(s)) if s == "radiance" => Transport::Radiance,
        Some(Value::String(s)) if s == "importance" => Transport::Importance,
        Some(v) => {
            return Err(Error::new(
                Status::UnknownName,
                format!(
                    "\"transport\": {v} is not valid; valid choices: \"radiance\", \"importance\""
                ),
            ));
        }
    };
    let lobes = obj
        .get("lobes")
        .and_then(Value::as_array)
        .ok_or_else(|| parse_error("the closure needs a \"lobes\" array".into()))?;
    if lobes.is_empty() {
        return Err(parse_error(
            "\"lobes\" is empty: a closure needs at least one lobe".into(),
        ));
    }
    let mut closure = Closure::new(wo, mode);
    for (i, lobe) in lobes.iter().enumerate() {
        let lobe = lobe
            .as_object()
            .ok_or_else(|| parse_error(format!("lobes[{i}] must be an object")))?;
        if lobe.contains_key(MATERIAL_KEY) {
            add_material(registry, &mut closure, lobe, Some(i), prune)?;
        } else {
            add_lobe(registry, &mut closure, lobe, i)?;
        }
    }
    closure.finish()?;
    Ok(closure)
}

fn add_lobe(
    registry: &Registry,
    closure: &mut Closure,
    lobe: &Map<String, Value>,
    i: usize,
) -> Result<(), Error> {
    let name = lobe.get("type").and_then(Value::as_str).ok_or_else(|| {
        parse_error(format!(
            "lobes[{i}] needs a \"type\" string; valid types: {}",
            registry.names().join(", ")
        ))
    })?;
    let type_id = registry.find(name)?;
    let lobe_type = registry.get(type_id)?;
    let specs = lobe_type.params();
    let at = |key: &str| format!("lobes[{i}] ({name}).{}", quoted(key));

    let (weight, frame) = placement(lobe, &at)?;
    let block = read_block(specs, lobe, LOBE_KEYS, name, &at)?;
    closure.add_lobe(registry, type_id, weight, frame, Some(&block))?;
    Ok(())
}

/// The `weight`, `normal` and `tangent` of a lobe or material entry.
fn placement(
    entry: &Map<String, Value>,
    at: &dyn Fn(&str) -> String,
) -> Result<([f32; 3], Frame), Error> {
    let weight = match entry.get("weight") {
        None => [1.0; 3],
        Some(v) => rgb(v, &at("weight"))?,
    };
    let normal = match entry.get("normal") {
        None => Vec3::splat(0.0, 0.0, 1.0),
        Some(v) => vector(v, &at("normal"))?,
    };
    // All zeros: automatic, as in the C API (`glint_frame`).
    let tangent = match entry.get("tangent") {
        None => None,
        Some(v) => match triple(v, &at("tangent"))? {
            t if t == [0.0; 3] => None,
            [x, y, z] => Some(Vec3::try_unit(x, y, z, &at("tangent"))?),
        },
    };
    Ok((weight, Frame::new(normal, tangent)))
}

/// A parameter block laid out by `specs`: the defaults, with every key of `entry`
/// but `reserved` set (an unknown key is an error listing the valid ones). A key is
/// an entry's full name (`coat.roughness`) or a top-level name; a group takes an
/// object of its members, an array a list of values, a table a list of row objects
/// (at most its capacity; the list's length is the count, cells not given keep their
/// defaults). Setting one value twice (`"coat": {...}` and `"coat.x"`) is an error.
fn read_block(
    specs: &[ParamSpec],
    entry: &Map<String, Value>,
    reserved: &[&str],
    name: &str,
    at: &dyn Fn(&str) -> String,
) -> Result<Vec<f32>, Error> {
    let mut reader = BlockReader {
        specs,
        block: vec![0.0f32; params::block_size(specs)],
        given: vec![false; specs.len()],
        name,
        at,
    };
    params::write_defaults(specs, &mut reader.block);
    for (key, value) in entry {
        if reserved.contains(&key.as_str()) {
            continue;
        }
        let index = specs
            .iter()
            .position(|s| s.name == key && s.shape != Shape::Column)
            .ok_or_else(|| {
                let valid: Vec<&str> = reserved
                    .iter()
                    .copied()
                    .chain(
                        specs
                            .iter()
                            .enumerate()
                            .filter(|&(i, _)| params::parent_of(specs, i).is_none())
                            .map(|(_, s)| s.name),
                    )
                    .collect();
                Error::new(
                    Status::UnknownName,
                    format!(
                        "{}: unknown key; valid keys for {name}: {}",
                        at(key),
                        valid.join(", ")
                    ),
                )
            })?;
        reader.entry(index, value)?;
    }
    Ok(reader.block)
}

/// A block being read from JSON; `given` marks the entries set so far.
struct BlockReader<'a> {
    specs: &'a [ParamSpec],
    block: Vec<f32>,
    given: Vec<bool>,
    name: &'a str,
    at: &'a dyn Fn(&str) -> String,
}

impl BlockReader<'_> {
    /// Set entry `index` (not a column) from `value`.
    fn entry(&mut self, index: usize, value: &Value) -> Result<(), Error> {
        let spec = &self.specs[index];
        let offset = params::offset_of(self.specs, index);
        let what = (self.at)(spec.name);
        match spec.shape {
            Shape::Value => self.value(index, 0, value, spec.name),
            Shape::Column => unreachable!("columns are read with their table"),
            Shape::Group => {
                let members = value.as_object().ok_or_else(|| {
                    parse_error(format!("{what}: expected an object, found {value}"))
                })?;
                for (key, v) in members {
                    let member = self.member(index, key)?;
                    self.entry(member, v)?;
                }
                Ok(())
            }
            Shape::Array => {
                let items = self.rows(index, value, "values")?;
                self.block[offset] = items.len() as f32;
                for (e, v) in items.iter().enumerate() {
                    self.value(index, e, v, &params::element_path(spec, e))?;
                }
                Ok(())
            }
            Shape::Table => {
                let rows = self.rows(index, value, "row objects")?;
                self.block[offset] = rows.len() as f32;
                for (r, row) in rows.iter().enumerate() {
                    let row = row.as_object().ok_or_else(|| {
                        parse_error(format!(
                            "{}: expected an object, found {row}",
                            (self.at)(&format!("{}[{r}]", spec.name))
                        ))
                    })?;
                    for (key, v) in row {
                        let column = self.member(index, key)?;
                        let path = params::element_path(&self.specs[column], r);
                        self.value(column, r, v, &path)?;
                    }
                }
                Ok(())
            }
        }
    }

    /// The list given for array or table `index`: at most its capacity; marks it given.
    fn rows<'v>(&mut self, index: usize, value: &'v Value, of: &str) -> Result<&'v [Value], Error> {
        let spec = &self.specs[index];
        let what = (self.at)(spec.name);
        let items = value.as_array().ok_or_else(|| {
            parse_error(format!(
                "{what}: expected a list of at most {} {of}, found {value}",
                spec.capacity
            ))
        })?;
        if items.len() > spec.capacity as usize {
            return Err(Error::new(
                Status::OutOfRange,
                format!(
                    "{what}: {} {of} given; {} holds at most {}",
                    items.len(),
                    spec.name,
                    spec.capacity
                ),
            ));
        }
        self.mark(index)?;
        Ok(items)
    }

    /// The direct member `key` of group or table `header`.
    fn member(&self, header: usize, key: &str) -> Result<usize, Error> {
        let spec = &self.specs[header];
        let members = header + 1..=header + spec.members as usize;
        let direct = |j: &usize| params::parent_of(self.specs, *j) == Some(header);
        let short = |j: usize| &self.specs[j].name[spec.name.len() + 1..];
        members
            .clone()
            .filter(direct)
            .find(|&j| short(j) == key)
            .ok_or_else(|| {
                let valid: Vec<&str> = members.filter(direct).map(short).collect();
                Error::new(
                    Status::UnknownName,
                    format!(
                        "{}: unknown key; valid keys for {}: {}",
                        (self.at)(&format!("{}.{key}", spec.name)),
                        spec.name,
                        valid.join(", ")
                    ),
                )
            })
    }

    /// An entry is set at most once (by its full name or inside its group).
    fn mark(&mut self, index: usize) -> Result<(), Error> {
        if std::mem::replace(&mut self.given[index], true) {
            return Err(parse_error(format!(
                "{}: given twice (by its full name and inside its group)",
                (self.at)(self.specs[index].name)
            )));
        }
        Ok(())
    }

    /// Element `element` of value entry `index` from `value`; `path` names it.
    fn value(
        &mut self,
        index: usize,
        element: usize,
        value: &Value,
        path: &str,
    ) -> Result<(), Error> {
        let spec = &self.specs[index];
        if !spec.repeated() {
            self.mark(index)?;
        }
        let at = params::offset_of(self.specs, index) + spec.element_offset(element);
        let what = (self.at)(path);
        match spec.kind {
            ParamKind::Float => self.block[at] = number(value, &what)?,
            ParamKind::Rgb => self.block[at..at + 3].copy_from_slice(&rgb(value, &what)?),
            ParamKind::Enum => {
                let choices = spec.choices;
                let choice = value.as_str().ok_or_else(|| {
                    parse_error(format!("{what}: expected one of {}", choices.join(", ")))
                })?;
                self.block[at] = spec.choice_index(self.name, choice)? as f32;
            }
        }
        Ok(())
    }
}

/// The material a document or entry names, compiled, and its `at` prefix.
fn read_material(
    registry: &Registry,
    entry: &Map<String, Value>,
    reserved: &[&str],
    index: Option<usize>,
    prune: f32,
) -> Result<Material, Error> {
    let prefix = index.map_or(String::new(), |i| format!("lobes[{i}] "));
    let name = entry
        .get(MATERIAL_KEY)
        .and_then(Value::as_str)
        .ok_or_else(|| {
            parse_error(format!(
                "{prefix}\"material\" must be a string; valid materials: {}",
                registry.material_names().join(", ")
            ))
        })?;
    let type_id = registry.find_material(name)?;
    let specs = registry.material(type_id)?.params();
    let at = |key: &str| format!("{prefix}({name}).{}", quoted(key));
    let block = read_block(specs, entry, reserved, name, &at)?;
    Material::new(registry, type_id, Some(&block), prune)
}

/// Expand a material entry (or a whole material document, `index` None) into
/// `closure` at its `wo` (normal incidence without one), its lobes scaled by the
/// entry's `weight`.
fn add_material(
    registry: &Registry,
    closure: &mut Closure,
    entry: &Map<String, Value>,
    index: Option<usize>,
    prune: f32,
) -> Result<(), Error> {
    let reserved = if index.is_some() {
        MATERIAL_ENTRY_KEYS
    } else {
        &MATERIAL_ENTRY_KEYS[..1]
    };
    let material = read_material(registry, entry, reserved, index, prune)?;
    let prefix = index.map_or(String::new(), |i| format!("lobes[{i}] "));
    let at = |key: &str| format!("{prefix}({}).{}", material.kind().name(), quoted(key));
    let (weight, frame) = placement(entry, &at)?;
    let owner = format!("{prefix}({})", material.kind().name());
    crate::closure::check_weight(&owner, weight)?;
    let wo = closure.view().unwrap_or(frame.n);
    let ctx = ShadingContext::new(wo, frame);
    let mut shares = [0.0; MAX_LOBES];
    let scale = Rgb::from_array(weight);
    let before = closure.lobes().len();
    material.emit(closure, &ctx, material.params(), scale, &mut shares)?;
    // The material's own weights (Disney's sheen tint up to 10) scale the entry's:
    // its lobes are held to the lobes' bound too.
    for lobe in &closure.lobes()[before..] {
        let w = lobe.weight;
        crate::closure::check_weight(&owner, [w.r, w.g, w.b])?;
    }
    Ok(())
}

/// Compile a material from its JSON document: `{"material": "disney", ...}`, every
/// other key a parameter of the material type's schema (as lobe parameters are read).
pub fn material_from_json(registry: &Registry, text: &str, prune: f32) -> Result<Material, Error> {
    let obj = parse_root(
        text,
        "a material description (with a \"material\" type name)",
    )?;
    if !obj.contains_key(MATERIAL_KEY) {
        return Err(parse_error(format!(
            "a material description needs a \"material\" key; valid materials: {}",
            registry.material_names().join(", ")
        )));
    }
    read_material(registry, &obj, &[MATERIAL_KEY], None, prune)
}

fn number(v: &Value, what: &str) -> Result<f32, Error> {
    v.as_f64()
        .map(|x| x as f32)
        .ok_or_else(|| parse_error(format!("{what}: expected a number, found {v}")))
}

fn triple(v: &Value, what: &str) -> Result<[f32; 3], Error> {
    match v.as_array() {
        Some(a) if a.len() == 3 => Ok([
            number(&a[0], what)?,
            number(&a[1], what)?,
            number(&a[2], what)?,
        ]),
        _ => Err(parse_error(format!(
            "{what}: expected [x, y, z], found {v}"
        ))),
    }
}

/// A color: one number for gray or `[r, g, b]`.
fn rgb(v: &Value, what: &str) -> Result<[f32; 3], Error> {
    if v.is_number() {
        Ok([number(v, what)?; 3])
    } else {
        triple(v, what)
    }
}

fn vector(v: &Value, what: &str) -> Result<Vec3<f32>, Error> {
    let [x, y, z] = triple(v, what)?;
    Vec3::try_unit(x, y, z, what)
}
