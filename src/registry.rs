//! Lobe types by id and by name. Built-in lobes are registered at runtime
//! creation; plugin lobes join the same table, so everything downstream
//! (closures, JSON, the C API, the verification harness) sees one list.
//!
//! Built-in lobe types are statics; a plugin's are allocated when it is loaded and
//! shared ([`LobeRef::Shared`]) by the registry and every closure built with them, so
//! they are freed with the last of those, never leaked.

use crate::error::{Error, Status};
use crate::lobes::conductor::Conductor;
use crate::lobes::dielectric::Dielectric;
use crate::lobes::disney_clearcoat::DisneyClearcoat;
use crate::lobes::disney_diffuse::DisneyDiffuse;
use crate::lobes::disney_sheen::DisneySheen;
use crate::lobes::disney_specular::DisneySpecular;
use crate::lobes::lambert::Lambert;
use crate::lobes::mirror::Mirror;
use crate::lobes::{Builtin, LobeType};
use crate::materials::{BUILTIN_MATERIALS, MaterialType};
use crate::params;
use std::ops::Deref;
use std::sync::Arc;

/// Every built-in lobe type, in registration (id) order.
pub static BUILTINS: &[&(dyn LobeType + 'static)] = &[
    &Builtin::<Lambert>::new(),
    &Builtin::<Conductor>::new(),
    &Builtin::<Dielectric>::new(),
    &Builtin::<Mirror>::new(),
    &Builtin::<DisneyDiffuse>::new(),
    &Builtin::<DisneySheen>::new(),
    &Builtin::<DisneySpecular>::new(),
    &Builtin::<DisneyClearcoat>::new(),
];

/// A lobe type as registries and closures hold it.
#[derive(Clone)]
pub enum LobeRef {
    /// A type that lives for the whole program (the built-ins): no reference count.
    Static(&'static dyn LobeType),
    /// A type allocated at run time (a plugin's), alive while a holder is.
    Shared(Arc<dyn LobeType>),
}

impl Deref for LobeRef {
    type Target = dyn LobeType;

    #[inline]
    fn deref(&self) -> &Self::Target {
        match self {
            LobeRef::Static(lobe) => *lobe,
            LobeRef::Shared(lobe) => &**lobe,
        }
    }
}

impl From<&'static dyn LobeType> for LobeRef {
    fn from(lobe: &'static dyn LobeType) -> Self {
        LobeRef::Static(lobe)
    }
}

/// The lobe types a runtime knows; ids are indices.
pub struct Registry {
    types: Vec<LobeRef>,
    /// Each type's [`params::Bounds`] (None for nested schemas), for `validate_block`.
    bounds: Vec<Option<params::Bounds>>,
    materials: Vec<&'static dyn MaterialType>,
}

impl Registry {
    /// A registry holding the built-in lobes.
    pub fn with_builtins() -> Registry {
        Registry {
            types: BUILTINS.iter().map(|&lobe| LobeRef::Static(lobe)).collect(),
            bounds: BUILTINS
                .iter()
                .map(|l| params::Bounds::of(l.params()))
                .collect(),
            materials: BUILTIN_MATERIALS.to_vec(),
        }
    }

    /// Add a lobe type; its name must be new.
    pub fn register(&mut self, lobe: impl Into<LobeRef>) -> Result<u32, Error> {
        let lobe = lobe.into();
        if self.find(lobe.name()).is_ok() {
            return Err(Error::new(
                Status::DuplicateName,
                format!(
                    "a lobe type named \"{}\" is already registered",
                    lobe.name()
                ),
            ));
        }
        self.bounds.push(params::Bounds::of(lobe.params()));
        self.types.push(lobe);
        Ok((self.types.len() - 1) as u32)
    }

    /// Add a material type; its name must be new and its schema well formed
    /// ([`crate::params::check_schema`]).
    pub fn register_material(&mut self, material: &'static dyn MaterialType) -> Result<u32, Error> {
        let invalid = |m: String| Error::new(Status::InvalidArgument, m);
        crate::params::check_schema(material.params())
            .map_err(|m| invalid(format!("material {}: {m}", material.name())))?;
        if self.find_material(material.name()).is_ok() {
            return Err(Error::new(
                Status::DuplicateName,
                format!(
                    "a material type named \"{}\" is already registered",
                    material.name()
                ),
            ));
        }
        self.materials.push(material);
        Ok((self.materials.len() - 1) as u32)
    }

    pub fn len(&self) -> usize {
        self.types.len()
    }

    pub fn is_empty(&self) -> bool {
        self.types.is_empty()
    }

    /// The lobe type with id `id`.
    pub fn get(&self, id: u32) -> Result<&LobeRef, Error> {
        self.types.get(id as usize).ok_or_else(|| {
            Error::new(
                Status::OutOfRange,
                format!(
                    "lobe type id {id} does not exist (the registry has {})",
                    self.len()
                ),
            )
        })
    }

    /// Check a full parameter block of lobe type `id` (an id [`Self::get`] accepted)
    /// as [`params::validate`] does, by its bounds first: the common, valid block costs
    /// a few instructions per value.
    pub fn validate_block(&self, id: u32, block: &[f32]) -> Result<(), Error> {
        let lobe = self.get(id)?;
        match &self.bounds[id as usize] {
            Some(bounds) if bounds.admits(block) => Ok(()),
            _ => params::validate(lobe.name(), lobe.params(), block),
        }
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
                        "unknown lobe type {}; valid types: {}",
                        crate::json::quoted(name),
                        self.names().join(", ")
                    ),
                )
            })
    }

    /// Names of all lobe types, in id order.
    pub fn names(&self) -> Vec<&str> {
        self.types.iter().map(|t| t.name()).collect()
    }

    pub fn iter(&self) -> impl Iterator<Item = &LobeRef> {
        self.types.iter()
    }

    /// The material type with id `id`.
    pub fn material(&self, id: u32) -> Result<&'static dyn MaterialType, Error> {
        self.materials.get(id as usize).copied().ok_or_else(|| {
            Error::new(
                Status::OutOfRange,
                format!(
                    "material type id {id} does not exist (the registry has {})",
                    self.materials.len()
                ),
            )
        })
    }

    /// The id of the material type named `name`; the error lists the valid names.
    pub fn find_material(&self, name: &str) -> Result<u32, Error> {
        self.materials
            .iter()
            .position(|m| m.name() == name)
            .map(|i| i as u32)
            .ok_or_else(|| {
                Error::new(
                    Status::UnknownName,
                    format!(
                        "unknown material type {}; valid types: {}",
                        crate::json::quoted(name),
                        self.material_names().join(", ")
                    ),
                )
            })
    }

    /// Names of all material types, in id order.
    pub fn material_names(&self) -> Vec<&str> {
        self.materials.iter().map(|m| m.name()).collect()
    }

    /// Material types, in id order.
    pub fn materials(&self) -> &[&'static dyn MaterialType] {
        &self.materials
    }
}
