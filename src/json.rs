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

use crate::closure::Closure;
use crate::error::{Error, Status};
use crate::lobes::Transport;
use crate::math::{Frame, Vec3};
use crate::params::{self, ParamKind};
use crate::registry::Registry;
use serde::de::{self, Deserialize, Deserializer, MapAccess, SeqAccess, Visitor};
use serde_json::{Map, Number, Value};

const LOBE_KEYS: &[&str] = &["type", "weight", "normal", "tangent"];
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

/// Build (and finish) a closure from its JSON description.
pub fn closure_from_json(
    registry: &Registry,
    text: &str,
    wo: Option<Vec3<f32>>,
) -> Result<Closure, Error> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let Strict(root) =
        serde_json::from_str(text).map_err(|e| parse_error(format!("malformed JSON: {e}")))?;
    let obj = root.as_object().ok_or_else(|| {
        parse_error("a closure description must be a JSON object with a \"lobes\" array".into())
    })?;
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
        add_lobe(registry, &mut closure, lobe, i)?;
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

    let weight = match lobe.get("weight") {
        None => [1.0; 3],
        Some(v) => rgb(v, &at("weight"))?,
    };
    let normal = match lobe.get("normal") {
        None => Vec3::splat(0.0, 0.0, 1.0),
        Some(v) => vector(v, &at("normal"))?,
    };
    // All zeros: automatic, as in the C API (`glint_frame`).
    let tangent = match lobe.get("tangent") {
        None => None,
        Some(v) => match triple(v, &at("tangent"))? {
            t if t == [0.0; 3] => None,
            [x, y, z] => Some(Vec3::try_unit(x, y, z, &at("tangent"))?),
        },
    };

    let mut block = vec![0.0f32; params::block_size(specs)];
    params::write_defaults(specs, &mut block);
    for (key, value) in lobe {
        if LOBE_KEYS.contains(&key.as_str()) {
            continue;
        }
        let index = specs.iter().position(|s| s.name == key).ok_or_else(|| {
            let valid: Vec<&str> = LOBE_KEYS
                .iter()
                .copied()
                .chain(specs.iter().map(|s| s.name))
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
        let spec = &specs[index];
        let offset = params::offset_of(specs, index);
        match spec.kind {
            ParamKind::Float => block[offset] = number(value, &at(key))?,
            ParamKind::Rgb => block[offset..offset + 3].copy_from_slice(&rgb(value, &at(key))?),
            ParamKind::Enum => {
                let choices = spec.choices;
                let choice = value.as_str().ok_or_else(|| {
                    parse_error(format!(
                        "{}: expected one of {}",
                        at(key),
                        choices.join(", ")
                    ))
                })?;
                block[offset] = spec.choice_index(name, choice)? as f32;
            }
        }
    }
    closure.add_lobe(
        registry,
        type_id,
        weight,
        Frame::new(normal, tangent),
        Some(&block),
    )?;
    Ok(())
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
