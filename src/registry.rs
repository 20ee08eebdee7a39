//! Lobe types by id and by name. Built-in lobes are registered at runtime
//! creation; plugin lobes will join the same table, so everything downstream
//! (closures, JSON, the C API, the verification harness) sees one list.

use crate::error::{Error, Status};
use crate::lobes::conductor::Conductor;
use crate::lobes::dielectric::Dielectric;
use crate::lobes::lambert::Lambert;
use crate::lobes::mirror::Mirror;
use crate::lobes::{Builtin, LobeType};

/// Every built-in lobe type, in registration (id) order.
pub static BUILTINS: [&(dyn LobeType + 'static); 4] = [
    &Builtin::<Lambert>::new(),
    &Builtin::<Conductor>::new(),
    &Builtin::<Dielectric>::new(),
    &Builtin::<Mirror>::new(),
];

/// The lobe types a runtime knows; ids are indices.
pub struct Registry {
    types: Vec<&'static dyn LobeType>,
}

impl Registry {
    /// A registry holding the built-in lobes.
    pub fn with_builtins() -> Registry {
        Registry {
            types: BUILTINS.to_vec(),
        }
    }

    /// Add a lobe type; its name must be new.
    pub fn register(&mut self, lobe: &'static dyn LobeType) -> Result<u32, Error> {
        if self.find(lobe.name()).is_ok() {
            return Err(Error::new(
                Status::DuplicateName,
                format!(
                    "a lobe type named \"{}\" is already registered",
                    lobe.name()
                ),
            ));
        }
        self.types.push(lobe);
        Ok((self.types.len() - 1) as u32)
    }

    pub fn len(&self) -> usize {
        self.types.len()
    }

    pub fn is_empty(&self) -> bool {
        self.types.is_empty()
    }

    /// The lobe type with id `id`.
    pub fn get(&self, id: u32) -> Result<&'static dyn LobeType, Error> {
        self.types.get(id as usize).copied().ok_or_else(|| {
            Error::new(
                Status::OutOfRange,
                format!(
                    "lobe type id {id} does not exist (the registry has {})",
                    self.len()
                ),
            )
        })
    }

    /// The id of the lobe type named `name`; the error lists the valid names.
    pub fn find(&self, name: &str) -> Result<u32, Error> {
        self.types
            .iter()
            .position(|t| t.name() == name)
            .map(|i| i as u32)
            .ok_or_else(|| {
                Error::new(
                    Status::UnknownName,
                    format!(
                        "unknown lobe type \"{name}\"; valid types: {}",
                        self.names().join(", ")
                    ),
                )
            })
    }

    /// Names of all lobe types, in id order.
    pub fn names(&self) -> Vec<&str> {
        self.types.iter().map(|t| t.name()).collect()
    }

    pub fn iter(&self) -> impl Iterator<Item = &'static dyn LobeType> + '_ {
        self.types.iter().copied()
    }
}
