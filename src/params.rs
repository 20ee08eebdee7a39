//! Parameter schemas: every lobe type describes its parameter block (names, types,
//! defaults, ranges) so that the C API, the JSON loader, UIs and the tests are all
//! driven from one table.
//!
//! A parameter block is a flat `f32` array with fixed offsets, whatever the schema's
//! nesting: a `float` takes one slot, an `rgb` three, an `enum` one slot holding the
//! index of the choice. A schema is a list of entries in pre-order ([`Shape`]): a
//! *group* header (no slots) is followed by its members, named `group.member`; an
//! *array* takes a count slot then `capacity` elements; a *table* header takes the row
//! count and is followed by its columns (`table.column`), each `capacity` elements
//! (column-major, so a column is read like an array). Arrays and tables hold at most
//! [`MAX_ROWS`] rows of `float` or `rgb`; groups hold values, arrays and tables but no
//! groups ([`check_schema`]).

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

/// Most rows an array or a table holds.
pub const MAX_ROWS: u32 = 16;

/// An override or lookup address: the entry index in the low bits, the element
/// (array element or table row) from this bit on.
pub const ELEMENT_SHIFT: u32 = 16;

/// How a schema entry repeats and nests.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// One value.
    Value,
    /// A count slot, then `capacity` values.
    Array,
    /// A header without slots; the next `members` entries belong to it.
    Group,
    /// A header holding the row count; the next `members` entries are its columns.
    Table,
    /// A table column: `capacity` values, one per row.
    Column,
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
    pub shape: Shape,
    /// Rows of an array, a table or a column; 0 for one value and groups.
    pub capacity: u32,
    /// Entries after a group or table header that belong to it (all descendants).
    pub members: u32,
    /// Default count of an array or table.
    pub count: u32,
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
            shape: Shape::Value,
            capacity: 0,
            members: 0,
            count: 0,
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
            shape: Shape::Value,
            capacity: 0,
            members: 0,
            count: 0,
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
            shape: Shape::Value,
            capacity: 0,
            members: 0,
            count: 0,
        }
    }

    /// A group header `name`: the next `members` entries (`name.member`) belong to it.
    pub const fn group(name: &'static str, members: u32, doc: &'static str) -> Self {
        ParamSpec {
            shape: Shape::Group,
            members,
            ..ParamSpec::float(name, 0.0, 0.0, 0.0, doc)
        }
    }

    /// A table header `name` of up to `capacity` rows (`count` by default); the next
    /// `members` entries are its columns (`name.column`, made with [`Self::column`]).
    pub const fn table(
        name: &'static str,
        members: u32,
        capacity: u32,
        count: u32,
        doc: &'static str,
    ) -> Self {
        ParamSpec {
            shape: Shape::Table,
            members,
            capacity,
            count,
            ..ParamSpec::float(name, 0.0, 0.0, 0.0, doc)
        }
    }

    /// This float or rgb as an array of up to `capacity` elements (`count` by
    /// default), each defaulting to the value's default.
    pub const fn array(self, capacity: u32, count: u32) -> Self {
        ParamSpec {
            shape: Shape::Array,
            capacity,
            count,
            ..self
        }
    }

    /// This float or rgb as a column of a table of `capacity` rows.
    pub const fn column(self, capacity: u32) -> Self {
        ParamSpec {
            shape: Shape::Column,
            capacity,
            ..self
        }
    }

    /// Slots the entry takes in the block (its members' not included).
    pub const fn span(&self) -> usize {
        let n = self.kind.size();
        let rows = self.capacity as usize;
        match self.shape {
            Shape::Value => n,
            Shape::Array => 1 + rows * n,
            Shape::Group => 0,
            Shape::Table => 1,
            Shape::Column => rows * n,
        }
    }

    /// Whether `v` is finite and in `[min, max]` (NaN is not), for float and rgb
    /// values; without branches, so that checks over rows vectorize.
    #[inline(always)]
    pub fn in_range(&self, v: f32) -> bool {
        (v.abs() <= f32::MAX) & (v >= self.min) & (v <= self.max)
    }

    /// Whether the entry holds `capacity` elements (arrays and table columns).
    pub const fn repeated(&self) -> bool {
        matches!(self.shape, Shape::Array | Shape::Column)
    }

    /// Offset of element `element` from the entry's offset (the count slot of an
    /// array comes first).
    pub const fn element_offset(&self, element: usize) -> usize {
        let first = match self.shape {
            Shape::Array => 1,
            _ => 0,
        };
        first + element * self.kind.size()
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

/// Offset of entry `index` in a block laid out by `specs` (of a repeated entry: its
/// span's start, see [`ParamSpec::element_offset`]).
pub const fn offset_of(specs: &[ParamSpec], index: usize) -> usize {
    let mut offset = 0;
    let mut i = 0;
    while i < index {
        offset += specs[i].span();
        i += 1;
    }
    offset
}

/// Number of `f32` slots in a block laid out by `specs`.
pub const fn block_size(specs: &[ParamSpec]) -> usize {
    offset_of(specs, specs.len())
}

/// Each entry with its offset, in schema order.
pub fn layout(specs: &[ParamSpec]) -> impl Iterator<Item = (usize, &ParamSpec)> + '_ {
    specs.iter().scan(0, |offset, s| {
        let at = *offset;
        *offset += s.span();
        Some((at, s))
    })
}

/// Whether two blocks of the same schema make the same enumerated choices.
pub fn same_choices(specs: &[ParamSpec], a: &[f32], b: &[f32]) -> bool {
    enum_offsets(specs).all(|at| a[at] == b[at])
}

/// Whether the schema has enumerated values (their choices are part of a closure's
/// shape).
pub fn has_choices(specs: &[ParamSpec]) -> bool {
    enum_offsets(specs).next().is_some()
}

/// Call `f` with each enumerated choice of `block`, in schema order.
pub fn for_each_choice(specs: &[ParamSpec], block: &[f32], mut f: impl FnMut(u32)) {
    for at in enum_offsets(specs) {
        f(block[at] as u32);
    }
}

/// Block offsets of the schema's enumerated values (enums are never repeated).
fn enum_offsets(specs: &[ParamSpec]) -> impl Iterator<Item = usize> + '_ {
    layout(specs)
        .filter(|(_, s)| s.kind == ParamKind::Enum && s.shape == Shape::Value)
        .map(|(at, _)| at)
}

/// Write the schema's defaults into `out` (which must hold `block_size(specs)` slots):
/// every element of arrays and columns, and the default counts.
pub fn write_defaults(specs: &[ParamSpec], out: &mut [f32]) {
    for (at, spec) in layout(specs) {
        let n = spec.kind.size();
        let slots = &mut out[at..at + spec.span()];
        match spec.shape {
            Shape::Group => {}
            Shape::Table => slots[0] = spec.count as f32,
            Shape::Value | Shape::Array | Shape::Column => {
                let (count, values) = slots.split_at_mut(spec.element_offset(0));
                count.fill(spec.count as f32);
                for v in values.chunks_exact_mut(n) {
                    v.copy_from_slice(&spec.default[..n]);
                }
            }
        }
    }
}

/// The path of element `element` of entry `spec` for messages: `name` for one value,
/// `name[3]` for an array element, `table[3].column` for a table cell.
pub fn element_path(spec: &ParamSpec, element: usize) -> String {
    match (spec.shape, spec.name.rsplit_once('.')) {
        (Shape::Array, _) | (Shape::Column, None) => format!("{}[{element}]", spec.name),
        (Shape::Column, Some((table, column))) => format!("{table}[{element}].{column}"),
        _ => spec.name.to_string(),
    }
}

/// Check every value of a block against its schema: finite, in range, enum indices
/// integral, counts whole numbers in `[0, capacity]`; every element of an array or
/// column is checked, used or not. The error names the owner (lobe or material) and
/// the element's path (`ramp[3].position`) with the valid range.
pub fn validate(owner: &str, specs: &[ParamSpec], block: &[f32]) -> Result<(), Error> {
    let expected = block_size(specs);
    if block.len() != expected {
        return Err(Error::new(
            Status::InvalidArgument,
            format!(
                "{owner}: parameter block has {} values, expected {expected}",
                block.len()
            ),
        ));
    }
    for (at, spec) in layout(specs) {
        let slots = &block[at..at + spec.span()];
        match spec.shape {
            Shape::Group => {}
            Shape::Table => check_count(owner, spec, slots[0])?,
            Shape::Value => check_values(owner, spec, slots, 0)?,
            Shape::Array | Shape::Column => {
                let (count, values) = slots.split_at(spec.element_offset(0));
                if let Some(&c) = count.first() {
                    check_count(owner, spec, c)?;
                }
                for (e, v) in values.chunks_exact(spec.kind.size()).enumerate() {
                    check_values(owner, spec, v, e)?;
                }
            }
        }
    }
    Ok(())
}

/// Per-value bounds of a flat schema (single values only): a check of whole blocks
/// that costs a few instructions per value, where [`validate`] walks the schema.
/// A block it refuses goes through [`validate`] for the message.
#[derive(Clone, Debug)]
pub struct Bounds {
    lo: Box<[f32]>,
    hi: Box<[f32]>,
    /// Enumerated values, which must be whole numbers.
    whole: Box<[bool]>,
}

impl Bounds {
    /// The bounds of `specs`; None when it has groups, arrays or tables.
    pub fn of(specs: &[ParamSpec]) -> Option<Bounds> {
        let (mut lo, mut hi, mut whole) = (Vec::new(), Vec::new(), Vec::new());
        for spec in specs {
            if spec.shape != Shape::Value {
                return None;
            }
            let (min, max, is_enum) = match spec.kind {
                ParamKind::Enum => (0.0, spec.choices.len() as f32 - 1.0, true),
                _ => (spec.min, spec.max, false),
            };
            for _ in 0..spec.kind.size() {
                lo.push(min);
                hi.push(max);
                whole.push(is_enum);
            }
        }
        Some(Bounds {
            lo: lo.into(),
            hi: hi.into(),
            whole: whole.into(),
        })
    }

    /// Whether [`validate`] accepts `block`: its size, and every value finite, in
    /// range and, for enums, whole.
    pub fn admits(&self, block: &[f32]) -> bool {
        block.len() == self.lo.len()
            && block
                .iter()
                .zip(self.lo.iter().zip(&self.hi))
                .zip(&self.whole)
                .all(|((&v, (&lo, &hi)), &whole)| {
                    v.is_finite() && v >= lo && v <= hi && (!whole || is_whole(v))
                })
    }
}

/// A count slot holds a whole number of rows in `[0, capacity]`.
fn check_count(owner: &str, spec: &ParamSpec, count: f32) -> Result<(), Error> {
    if (0.0..=spec.capacity as f32).contains(&count) && is_whole(count) {
        return Ok(());
    }
    Err(Error::new(
        Status::OutOfRange,
        format!(
            "{owner}.{}: count {count} is not a whole number in [0, {}]",
            spec.name, spec.capacity
        ),
    ))
}

/// The values of one element (of `spec`, at `element`) are finite and in range.
pub fn check_values(
    owner: &str,
    spec: &ParamSpec,
    values: &[f32],
    element: usize,
) -> Result<(), Error> {
    for &v in values {
        if !v.is_finite() {
            return Err(Error::new(
                Status::InvalidArgument,
                format!(
                    "{owner}.{}: value {v} is not finite",
                    element_path(spec, element)
                ),
            ));
        }
        if spec.kind == ParamKind::Enum {
            let choices = spec.choices;
            if v < 0.0 || v as usize >= choices.len() || !is_whole(v) {
                return Err(Error::new(
                    Status::OutOfRange,
                    format!(
                        "{owner}.{}: {v} is not a choice index; valid: 0..{} ({})",
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
                    "{owner}.{}: {v} is outside its range [{}, {}]",
                    element_path(spec, element),
                    spec.min,
                    spec.max
                ),
            ));
        }
    }
    Ok(())
}

/// `v` (in [0, 2^32)) has no fraction. Not `f32::fract`: without SSE4.1 (the baseline
/// ISA) that is a libm `truncf` call, on every parameter validated.
#[inline(always)]
fn is_whole(v: f32) -> bool {
    v == (v as u32) as f32
}

/// One value of a block, resolved from an address ([`ELEMENT_SHIFT`]).
#[derive(Clone, Copy, Debug)]
pub struct Slot<'a> {
    pub spec: &'a ParamSpec,
    pub index: usize,
    pub element: usize,
    /// Block offset of the value's first float.
    pub offset: usize,
}

/// The address of element `element` of entry `index`.
pub const fn address(index: u32, element: u32) -> u32 {
    index | element << ELEMENT_SHIFT
}

/// The value at `address` (entry index, element): an error for a missing entry, a
/// group or table header, an element beyond the capacity or an element of a single
/// value. `what` prefixes the message (e.g. `overrides[2]`).
pub fn locate<'a>(
    owner: &str,
    specs: &'a [ParamSpec],
    address: u32,
    what: &dyn std::fmt::Display,
) -> Result<Slot<'a>, Error> {
    let index = (address & ((1 << ELEMENT_SHIFT) - 1)) as usize;
    let element = (address >> ELEMENT_SHIFT) as usize;
    let spec = specs.get(index).ok_or_else(|| {
        Error::new(
            Status::OutOfRange,
            format!(
                "{what}: parameter index {index} does not exist ({owner} has {} parameters)",
                specs.len()
            ),
        )
    })?;
    let rows = if spec.repeated() { spec.capacity } else { 1 };
    if matches!(spec.shape, Shape::Group | Shape::Table) {
        return Err(Error::new(
            Status::InvalidArgument,
            format!(
                "{what}: {owner}.{} is a {}; address its members",
                spec.name,
                if spec.shape == Shape::Group {
                    "group"
                } else {
                    "table"
                }
            ),
        ));
    }
    if element >= rows as usize {
        return Err(Error::new(
            Status::OutOfRange,
            format!(
                "{what}: element {element} of {owner}.{} does not exist (it has {rows})",
                spec.name
            ),
        ));
    }
    Ok(Slot {
        spec,
        index,
        element,
        offset: offset_of(specs, index) + spec.element_offset(element),
    })
}

/// The address of the parameter named `name`: an entry's full dotted name
/// (`coat.roughness`, `ramp`), an array element (`weights[2]`) or a table cell
/// (`ramp[3].position`). The error lists the valid names.
pub fn find(owner: &str, specs: &[ParamSpec], name: &str) -> Result<u32, Error> {
    let entry = |n: &str| specs.iter().position(|s| s.name == n);
    let found = match entry(name) {
        Some(i) => Some((i, 0)),
        None => element_name(name).and_then(|(base, element)| {
            let i = entry(&base)?;
            let s = &specs[i];
            // `ramp[3].position` names a column; `weights[2]` an array.
            let array_form = !name.ends_with(']');
            (s.repeated() && array_form == (s.shape == Shape::Column)).then_some((i, element))
        }),
    };
    let unknown = || {
        let names: Vec<&str> = specs.iter().map(|p| p.name).collect();
        Error::new(
            Status::UnknownName,
            format!(
                "{owner} has no parameter {}; valid: {}",
                crate::json::quoted(name),
                names.join(", ")
            ),
        )
    };
    let (index, element) = found.ok_or_else(unknown)?;
    let rows = specs[index].capacity.max(1) as usize;
    if element >= rows || index >= 1 << ELEMENT_SHIFT {
        return Err(Error::new(
            Status::OutOfRange,
            format!(
                "{owner}.{name}: element {element} is beyond {}'s {rows} rows",
                specs[index].name
            ),
        ));
    }
    Ok(address(index as u32, element as u32))
}

/// `a[3].b` -> (`a.b`, 3); `a[3]` -> (`a`, 3).
fn element_name(name: &str) -> Option<(String, usize)> {
    let (before, rest) = name.split_once('[')?;
    let (digits, after) = rest.split_once(']')?;
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) || digits.len() > 5 {
        return None;
    }
    if !(after.is_empty() || after.starts_with('.')) {
        return None;
    }
    Some((format!("{before}{after}"), digits.parse().ok()?))
}

/// The group or table entry `index` belongs to, if any.
pub fn parent_of(specs: &[ParamSpec], index: usize) -> Option<usize> {
    (0..index)
        .rev()
        .find(|&h| h + specs[h].members as usize >= index)
}

/// Check a schema's structure: headers' members in range and named `header.member`
/// (the short name without `.`, `[` or `]`), groups not nested, tables holding only
/// columns of their capacity, arrays and columns of `float` or `rgb` with 1 to
/// [`MAX_ROWS`] rows, default counts within the capacity, names unique, ranges finite
/// and defaults inside them. Flat schemas pass when their names are distinct and their
/// defaults in range.
pub fn check_schema(specs: &[ParamSpec]) -> Result<(), String> {
    if specs.len() >= 1 << ELEMENT_SHIFT {
        return Err(format!("{} entries is too many", specs.len()));
    }
    let mut i = 0;
    while i < specs.len() {
        i = check_entry(specs, i, None)?;
    }
    for (i, s) in specs.iter().enumerate() {
        if specs[..i].iter().any(|t| t.name == s.name) {
            return Err(format!("{} is declared twice", s.name));
        }
    }
    Ok(())
}

/// Check entry `i` (inside `parent`) and its members; returns the next entry's index.
fn check_entry(specs: &[ParamSpec], i: usize, parent: Option<&ParamSpec>) -> Result<usize, String> {
    let s = &specs[i];
    let short = match parent {
        None => Some(s.name),
        Some(p) => s
            .name
            .strip_prefix(p.name)
            .and_then(|rest| rest.strip_prefix('.')),
    };
    let name = s.name;
    if !short.is_some_and(|n| !n.is_empty() && !n.contains(['.', '[', ']'])) {
        return Err(format!(
            "{name}: a name is `member` or `header.member` without '.', '[' or ']' in member"
        ));
    }
    let in_table = parent.is_some_and(|p| p.shape == Shape::Table);
    match (s.shape, parent.map(|p| p.shape)) {
        (Shape::Column, Some(Shape::Table)) => {}
        (Shape::Column, _) => return Err(format!("{name}: a column outside a table")),
        (_, Some(Shape::Table)) => return Err(format!("{name}: a table holds only columns")),
        (Shape::Group, Some(_)) => return Err(format!("{name}: groups do not nest")),
        _ => {}
    }
    let repeated = matches!(s.shape, Shape::Array | Shape::Table | Shape::Column);
    if repeated && !(1..=MAX_ROWS).contains(&s.capacity) {
        return Err(format!(
            "{name}: capacity {} is not in [1, {MAX_ROWS}]",
            s.capacity
        ));
    }
    if !repeated && s.capacity != 0 {
        return Err(format!("{name}: only arrays and tables have a capacity"));
    }
    if s.count > s.capacity {
        return Err(format!(
            "{name}: default count {} > capacity {}",
            s.count, s.capacity
        ));
    }
    if in_table && parent.is_some_and(|p| p.capacity != s.capacity) {
        return Err(format!(
            "{name}: a column's capacity differs from its table's"
        ));
    }
    if s.repeated() && s.kind == ParamKind::Enum {
        return Err(format!(
            "{name}: arrays and columns hold float or rgb values"
        ));
    }
    if matches!(s.shape, Shape::Group | Shape::Table) {
        let end = i + 1 + s.members as usize;
        if s.members == 0 || end > specs.len() {
            return Err(format!(
                "{name}: {} members do not fit the schema",
                s.members
            ));
        }
        let mut j = i + 1;
        while j < end {
            j = check_entry(specs, j, Some(s))?;
        }
        if j != end {
            return Err(format!("{name}: its last member's own members run past it"));
        }
        return Ok(end);
    }
    if s.members != 0 {
        return Err(format!("{name}: only groups and tables have members"));
    }
    let n = s.kind.size();
    let bad_default = s.default[..n].iter().any(|v| !(s.min..=s.max).contains(v));
    if !(s.min.is_finite() && s.max.is_finite() && s.min <= s.max) || bad_default {
        return Err(format!(
            "{name}: range [{}, {}] or default out of order",
            s.min, s.max
        ));
    }
    Ok(i + 1)
}
