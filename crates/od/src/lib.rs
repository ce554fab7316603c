//! The CANopen object dictionary (CiA 301 §7.4), built at runtime.
//!
//! Objects hold typed sub-objects with access rules, limits, defaults,
//! persistence groups and PDO mappability. Every checked access returns the
//! exact [`SdoAbort`] code a server must send. Application behaviour attaches
//! through [`ObjectHooks`]; hot paths use resolved [`EntryRef`] handles.
#![cfg_attr(not(feature = "std"), no_std)]

extern crate alloc;

mod abort;
mod bytes;
mod dict;
mod typed;
mod types;
mod value;

pub use abort::SdoAbort;
pub use dict::{EntryRef, NoHooks, Object, ObjectDictionary, ObjectHooks, SubObject, WriteOutcome};
pub use typed::{Typed, TypedHooks};
pub use types::{
    ALL_DATA_TYPES, Access, DataType, NumKind, ObjectCode, PersistGroup, check_len, compare_le, le_i64,
    le_u64,
};
pub use value::{ParseValueError, Value, parse_int};
