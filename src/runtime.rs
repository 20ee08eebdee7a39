//! The runtime: the root object that owns the lobe registry and the settings.
//! Read-only after setup, so it can be shared by every thread.

use crate::error::{Error, Status};
use crate::registry::Registry;

/// Which kernel set batch calls use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Isa {
    /// The best the machine supports.
    Auto,
    Scalar,
}

/// Settings from the configuration string.
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    pub isa: Isa,
}

impl Default for Settings {
    fn default() -> Self {
        Settings { isa: Isa::Auto }
    }
}

/// Configuration keys `Settings::parse` accepts.
pub const CONFIG_KEYS: &[&str] = &["isa"];

impl Settings {
    /// Parse `key=value` pairs separated by whitespace, commas or semicolons.
    /// Unknown keys and bad values are errors that name the valid ones.
    pub fn parse(config: &str) -> Result<Settings, Error> {
        let mut settings = Settings::default();
        for item in config
            .split([' ', '\t', '\n', ',', ';'])
            .filter(|s| !s.is_empty())
        {
            let (key, value) = item.split_once('=').ok_or_else(|| {
                Error::new(
                    Status::Parse,
                    format!(
                        "config item \"{item}\" is not key=value; valid keys: {}",
                        CONFIG_KEYS.join(", ")
                    ),
                )
            })?;
            match key {
                "isa" => {
                    settings.isa = match value {
                        "auto" => Isa::Auto,
                        "scalar" => Isa::Scalar,
                        "avx2" | "avx512" => {
                            return Err(Error::new(
                                Status::Unsupported,
                                format!(
                                    "isa={value}: this build has only the scalar kernels; valid: auto, scalar"
                                ),
                            ));
                        }
                        _ => {
                            return Err(Error::new(
                                Status::OutOfRange,
                                format!("isa={value}: valid values: auto, scalar, avx2, avx512"),
                            ));
                        }
                    }
                }
                _ => {
                    return Err(Error::new(
                        Status::UnknownName,
                        format!(
                            "unknown config key \"{key}\"; valid keys: {}",
                            CONFIG_KEYS.join(", ")
                        ),
                    ));
                }
            }
        }
        Ok(settings)
    }
}

/// The registry and settings a host creates once.
pub struct Runtime {
    pub registry: Registry,
    pub settings: Settings,
}

impl Runtime {
    pub fn new(config: &str) -> Result<Runtime, Error> {
        Ok(Runtime {
            registry: Registry::with_builtins(),
            settings: Settings::parse(config)?,
        })
    }
}
