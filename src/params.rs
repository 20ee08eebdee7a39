//! Parameter schemas: every lobe type describes its parameter block (names, types,
//! defaults, ranges) so that the C API, the JSON loader, UIs and the tests are all
//! driven from one table.
//!
//! A parameter block is a flat `f32` array: a `float` takes one slot, an `rgb`
//! three, an `enum` one slot holding the index of the choice.

use crate::error::{Error, Status};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ParamKind {
    Float,
    Rgb,
    /// One of the named choices ([`ParamSpec::choices`]), stored as its index.
    Enum,
}

impl ParamKind {
    /// Slots the parameter takes in the block.
    pub const fn size(self) -> usize {
        match self {
            ParamKind::Float | ParamKind::Enum => 1,
            ParamKind::Rgb => 3,
        }
    }
}

/// One parameter of a lobe type.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParamSpec {
    pub name: &'static str,
    pub kind: ParamKind,
    /// The names of an `enum`'s choices; empty otherwise. A field rather than the
    /// variant's payload: a `Float` or `Rgb` variant built at run time (plugin schemas)
    /// would leave a payload's bytes uninitialized, and optimized code reading the kind
    /// loaded them speculatively (valgrind reported the branch).
    pub choices: &'static [&'static str],
    /// Default value (all three channels for `rgb`, the choice index for `enum`).
    pub default: [f32; 3],
    /// Valid range of each component (inclusive); for `enum`, `[0, choices - 1]`.
    pub min: f32,
    pub max: f32,
    pub doc: &'static str,
}

impl ParamSpec {
    pub const fn float(
        name: &'static str,
        default: f32,
        min: f32,
        max: f32,
        doc: &'static str,
    ) -> Self {
        ParamSpec {
            name,
            kind: ParamKind::Float,
            choices: &[],
            default: [default; 3],
            min,
            max,
            doc,
        }
    }
    pub const fn rgb(
        name: &'static str,
        default: [f32; 3],
        min: f32,
        max: f32,
        doc: &'static str,
    ) -> Self {
        ParamSpec {
            name,
            kind: ParamKind::Rgb,
            choices: &[],
            default,
            min,
            max,
            doc,
        }
    }
    pub const fn choice(
        name: &'static str,
        choices: &'static [&'static str],
        default: usize,
        doc: &'static str,
    ) -> Self {
        ParamSpec {
            name,
            kind: ParamKind::Enum,
            choices,
            default: [default as f32; 3],
            min: 0.0,
            max: (choices.len() - 1) as f32,
            doc,
        }
    }

    /// The enum choices, empty for numeric parameters.
    pub fn choices(&self) -> &'static [&'static str] {
        self.choices
    }

    /// Index of a choice by name, with an error listing the valid ones.
    pub fn choice_index(&self, lobe: &str, value: &str) -> Result<usize, Error> {
        let choices = self.choices();
        choices.iter().position(|c| *c == value).ok_or_else(|| {
            Error::new(
                Status::UnknownName,
                format!(
                    "{lobe}.{}: unknown choice {}; valid choices: {}",
                    self.name,
                    crate::json::quoted(value),
                    choices.join(", ")
                ),
            )
        })
    }
}

/// Offset of parameter `index` in a block laid out by `specs`.
pub const fn offset_of(specs: &[ParamSpec], index: usize) -> usize {
    let mut offset = 0;
    let mut i = 0;
    while i < index {
        offset += specs[i].kind.size();
        i += 1;
    }
    offset
}

/// Number of `f32` slots in a block laid out by `specs`.
pub const fn block_size(specs: &[ParamSpec]) -> usize {
    offset_of(specs, specs.len())
}

/// Whether two blocks of the same schema make the same enumerated choices.
pub fn same_choices(specs: &[ParamSpec], a: &[f32], b: &[f32]) -> bool {
    enum_offsets(specs).all(|at| a[at] == b[at])
}

/// Call `f` with each enumerated choice of `block`, in schema order.
pub fn for_each_choice(specs: &[ParamSpec], block: &[f32], mut f: impl FnMut(u32)) {
    for at in enum_offsets(specs) {
        f(block[at] as u32);
    }
}

/// Block offsets of the schema's enumerated parameters.
fn enum_offsets(specs: &[ParamSpec]) -> impl Iterator<Item = usize> + '_ {
    specs
        .iter()
        .scan(0, |offset, s| {
            let at = *offset;
            *offset += s.kind.size();
            Some((at, s.kind == ParamKind::Enum))
        })
        .filter_map(|(at, is_enum)| is_enum.then_some(at))
}

/// Write the schema's defaults into `out` (which must hold `block_size(specs)` slots).
pub fn write_defaults(specs: &[ParamSpec], out: &mut [f32]) {
    let mut offset = 0;
    for spec in specs {
        let n = spec.kind.size();
        out[offset..offset + n].copy_from_slice(&spec.default[..n]);
        offset += n;
    }
}

/// Check every value of a block against its schema: finite, in range, and enum
/// indices integral. The error names the lobe, the parameter and the valid range.
pub fn validate(lobe: &str, specs: &[ParamSpec], block: &[f32]) -> Result<(), Error> {
    let expected = block_size(specs);
    if block.len() != expected {
        return Err(Error::new(
            Status::InvalidArgument,
            format!(
                "{lobe}: parameter block has {} values, expected {expected}",
                block.len()
            ),
        ));
    }
    let mut offset = 0;
    for spec in specs {
        let n = spec.kind.size();
        for &v in &block[offset..offset + n] {
            if !v.is_finite() {
                return Err(Error::new(
                    Status::InvalidArgument,
                    format!("{lobe}.{}: value {v} is not finite", spec.name),
                ));
            }
            if spec.kind == ParamKind::Enum {
                let choices = spec.choices;
                if v.fract() != 0.0 || v < 0.0 || v as usize >= choices.len() {
                    return Err(Error::new(
                        Status::OutOfRange,
                        format!(
                            "{lobe}.{}: {v} is not a choice index; valid: 0..{} ({})",
                            spec.name,
                            choices.len() - 1,
                            choices.join(", ")
                        ),
                    ));
                }
            } else if v < spec.min || v > spec.max {
                return Err(Error::new(
                    Status::OutOfRange,
                    format!(
                        "{lobe}.{}: {v} is outside its range [{}, {}]",
                        spec.name, spec.min, spec.max
                    ),
                ));
            }
        }
        offset += n;
    }
    Ok(())
}
