//! Process-lifetime copies of the few `'static` values a plugin's schema needs: the
//! schema types ([`crate::params::ParamSpec`] enum choices, [`crate::lobes::VerifyCase`]
//! names and settings) borrow static data, as a built-in's do. Each distinct value is
//! stored once however often plugins are loaded, and stays reachable from here, so the
//! memory is bounded by what the loaded libraries (never unloaded) declare and nothing
//! is lost. Everything else a plugin lobe owns is freed with it.

use std::any::Any;
use std::sync::{Mutex, PoisonError};

static VALUES: Mutex<Vec<&'static (dyn Any + Send + Sync)>> = Mutex::new(Vec::new());

/// The stored value equal to `value`, stored now if there is none.
pub fn intern<T: PartialEq + Send + Sync + 'static>(value: T) -> &'static T {
    let mut values = VALUES.lock().unwrap_or_else(PoisonError::into_inner);
    if let Some(found) = values
        .iter()
        .find_map(|v| v.downcast_ref::<T>().filter(|v| **v == value))
    {
        return found;
    }
    let stored: &'static T = Box::leak(Box::new(value));
    values.push(stored);
    stored
}

/// A process-lifetime copy of `s`: interned values hold only these, never a string
/// that points into a declaration (whose memory is the plugin's, or a fuzzer's).
pub fn intern_str(s: &str) -> &'static str {
    intern(s.to_string()).as_str()
}
