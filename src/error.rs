//! Status codes and errors shared by the Rust API and the C ABI.

use std::borrow::Cow;
use std::ffi::CStr;
use std::fmt;

/// Why a call failed. The numeric values are the C API's `GLINT_*` status codes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum Status {
    Ok = 0,
    NullPointer = 1,
    InvalidArgument = 2,
    OutOfRange = 3,
    UnknownName = 4,
    Parse = 5,
    StructSize = 6,
    ArenaFull = 7,
    ClosureFull = 8,
    InvalidState = 9,
    Unsupported = 10,
    NoSample = 11,
    Panic = 12,
    PluginNotFound = 13,
    PluginNotLibrary = 14,
    PluginNoEntry = 15,
    PluginAbiRefused = 16,
    DuplicateName = 17,
    PluginParams = 18,
    PluginBlockSize = 19,
    InvalidHandle = 20,
    OutOfMemory = 21,
}

impl Status {
    pub const ALL: [Status; 22] = [
        Status::Ok,
        Status::NullPointer,
        Status::InvalidArgument,
        Status::OutOfRange,
        Status::UnknownName,
        Status::Parse,
        Status::StructSize,
        Status::ArenaFull,
        Status::ClosureFull,
        Status::InvalidState,
        Status::Unsupported,
        Status::NoSample,
        Status::Panic,
        Status::PluginNotFound,
        Status::PluginNotLibrary,
        Status::PluginNoEntry,
        Status::PluginAbiRefused,
        Status::DuplicateName,
        Status::PluginParams,
        Status::PluginBlockSize,
        Status::InvalidHandle,
        Status::OutOfMemory,
    ];

    /// A static description, NUL-terminated so the C API can hand it out as is.
    pub fn description(self) -> &'static CStr {
        match self {
            Status::Ok => c"success",
            Status::NullPointer => c"a required pointer argument is NULL",
            Status::InvalidArgument => {
                c"invalid argument (NaN, infinite, zero-length or malformed)"
            }
            Status::OutOfRange => c"a value is outside its valid range",
            Status::UnknownName => c"unknown name (lobe type, parameter, choice or config key)",
            Status::Parse => c"malformed input text (JSON or config)",
            Status::StructSize => c"struct_size is smaller than the structure this library needs",
            Status::ArenaFull => c"the arena has no room for another closure",
            Status::ClosureFull => c"the closure has no room for another lobe",
            Status::InvalidState => c"the object is not in a state that allows this call",
            Status::Unsupported => c"not supported by this build or machine",
            Status::NoSample => c"no sample: the closure cannot scatter from this direction",
            Status::Panic => c"internal error (a panic was caught at the API boundary)",
            Status::PluginNotFound => c"plugin file not found",
            Status::PluginNotLibrary => c"plugin file is not a loadable shared library",
            Status::PluginNoEntry => c"plugin does not export glint_plugin_entry",
            Status::PluginAbiRefused => {
                c"plugin ABI version refused (by the plugin or by this library)"
            }
            Status::DuplicateName => c"a lobe type with this name is already registered",
            Status::PluginParams => c"malformed plugin lobe declaration or parameter table",
            Status::PluginBlockSize => {
                c"plugin parameter block size or alignment does not match its table"
            }
            Status::InvalidHandle => {
                c"the handle was destroyed, reset or never created by this library"
            }
            Status::OutOfMemory => c"out of memory: a buffer the call needs could not be allocated",
        }
    }
}

/// A status with a message naming what was wrong.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Error {
    pub status: Status,
    pub message: Cow<'static, str>,
}

impl Error {
    pub fn new(status: Status, message: impl Into<Cow<'static, str>>) -> Self {
        Error {
            status,
            message: message.into(),
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.message)
    }
}

impl std::error::Error for Error {}
