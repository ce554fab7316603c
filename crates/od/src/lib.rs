//! The CANopen object dictionary (CiA 301 §7.4), built at runtime.
//!
//! Objects hold typed sub-objects with access rules, limits, defaults,
//! persistence groups and PDO mappability. Every checked access returns the
//! exact [`SdoAbort`] code a server must send. Each sub-object names its
//! [`Owner`]; writes run one documented path through it ([`owner`]); hot
//! paths use resolved [`EntryRef`] handles.
#![cfg_attr(not(feature = "std"), no_std)]

extern crate alloc;

mod abort;
mod bytes;
mod dict;
pub mod owner;
mod typed;
mod types;
mod value;

pub use abort::SdoAbort;
pub use dict::{EntryRef, Object, ObjectDictionary, SubObject};
pub use owner::{NoHooks, ObjectHooks, Owner, Target, WriteOutcome};
pub use typed::{Typed, TypedHooks};
pub use types::{
    ALL_DATA_TYPES, Access, DataType, NumKind, ObjectCode, PersistGroup, check_len, compare_le, le_i64,
    le_u64,
};
pub use value::{ParseValueError, Value, parse_int};
