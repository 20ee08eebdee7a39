//! The runtime: the root object that owns the lobe registry, the settings, the
//! kernel set and the worker threads. Read-only after setup, so it can be shared by
//! every thread.

use crate::batch::{Exec, Threads};
use crate::error::{Error, Status};
use crate::kernels::delay::Stores;
use crate::plugin;
use crate::registry::Registry;
use crate::simd::{Isa, Kernels};
use std::path::Path;

/// Which kernel set batch calls use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IsaSetting {
    /// The widest ISA the machine supports.
    Auto,
    /// This one; creating the runtime fails when the machine lacks it.
    Only(Isa),
}

/// Settings from the configuration string.
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    pub isa: IsaSetting,
    /// Threads for large batches: 0 = rayon's global pool (one per core), 1 = the
    /// calling thread only, N = a pool of N threads owned by the runtime.
    pub threads: usize,
    /// A directory whose `*.so` plugins are loaded when the runtime is created.
    pub plugins: Option<String>,
    /// Materials do not emit a lobe whose `luminance(weight * albedo(wo))` (its albedo
    /// estimate, `Model::albedo_estimate`) is below
    /// this (`prune=`, in [0, 1]; default `materials::DEFAULT_PRUNE`).
    pub prune: f32,
    /// Whether the fused kernels hold their outputs back, after later loads
    /// (`stores=`: `auto`, `held`, `direct`; see `kernels::delay::Stores`).
    pub stores: Stores,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            isa: IsaSetting::Auto,
            threads: 0,
            plugins: None,
            prune: crate::materials::DEFAULT_PRUNE,
            stores: Stores::Auto,
        }
    }
}

/// Configuration keys `Settings::parse` accepts.
pub const CONFIG_KEYS: &[&str] = &["isa", "threads", "plugins", "prune", "stores"];

/// Most threads `threads=N` accepts.
pub const MAX_THREADS: usize = 1024;

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
                        "auto" => IsaSetting::Auto,
                        _ => IsaSetting::Only(
                            Isa::ALL
                                .into_iter()
                                .find(|isa| isa.name() == value)
                                .ok_or_else(|| {
                                    Error::new(
                                        Status::OutOfRange,
                                        format!(
                                            "isa={value}: valid values: auto, scalar, avx2, avx512"
                                        ),
                                    )
                                })?,
                        ),
                    }
                }
                "threads" => {
                    settings.threads = value
                        .parse::<usize>()
                        .ok()
                        .filter(|&n| n <= MAX_THREADS)
                        .ok_or_else(|| {
                            Error::new(
                                Status::OutOfRange,
                                format!(
                                    "threads={value}: valid values: 0 (one per core), 1 (the calling thread only) .. {MAX_THREADS}"
                                ),
                            )
                        })?
                }
                "plugins" => settings.plugins = Some(value.to_string()),
                "prune" => {
                    settings.prune = value
                        .parse::<f32>()
                        .ok()
                        .filter(|p| (0.0..=1.0).contains(p))
                        .ok_or_else(|| {
                            Error::new(
                                Status::OutOfRange,
                                format!("prune={value}: valid values: a number in [0, 1]"),
                            )
                        })?
                }
                "stores" => {
                    settings.stores = Stores::ALL
                        .into_iter()
                        .find(|s| s.name() == value)
                        .ok_or_else(|| {
                            Error::new(
                                Status::OutOfRange,
                                format!("stores={value}: valid values: auto, held, direct"),
                            )
                        })?
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

/// The registry, settings, kernels and threads a host creates once.
pub struct Runtime {
    pub registry: Registry,
    pub settings: Settings,
    kernels: Kernels,
    pool: Option<rayon::ThreadPool>,
}

impl Runtime {
    pub fn new(config: &str) -> Result<Runtime, Error> {
        let settings = Settings::parse(config)?;
        let kernels = match settings.isa {
            IsaSetting::Auto => Kernels::best(),
            IsaSetting::Only(isa) => Kernels::new(isa)?,
        }
        .with_stores(settings.stores);
        let pool = match settings.threads {
            0 | 1 => None,
            n => Some(
                rayon::ThreadPoolBuilder::new()
                    .num_threads(n)
                    .thread_name(|i| format!("glint-{i}"))
                    .build()
                    .map_err(|e| {
                        Error::new(
                            Status::Unsupported,
                            format!("threads={n}: cannot start the thread pool: {e}"),
                        )
                    })?,
            ),
        };
        let mut runtime = Runtime {
            registry: Registry::with_builtins(),
            settings,
            kernels,
            pool,
        };
        if let Some(dir) = runtime.settings.plugins.clone() {
            for path in plugin::plugins_in(Path::new(&dir))? {
                runtime.load_plugin(&path)?;
            }
        }
        Ok(runtime)
    }

    /// Load a plugin and register its lobe types (see `crate::plugin`); returns their
    /// ids. On error nothing is registered.
    pub fn load_plugin(&mut self, path: &Path) -> Result<Vec<u32>, Error> {
        plugin::load(&mut self.registry, path)
    }

    /// The kernel set batch calls use.
    pub fn kernels(&self) -> Kernels {
        self.kernels
    }

    /// How batch calls on closures of this runtime run.
    pub fn exec(&self) -> Exec<'_> {
        Exec {
            kernels: self.kernels,
            threads: match (&self.pool, self.settings.threads) {
                (Some(pool), _) => Threads::Pool(pool),
                (None, 1) => Threads::Caller,
                (None, _) => Threads::Global,
            },
        }
    }
}
