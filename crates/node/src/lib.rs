//! A complete CiA 301 device: composes the services over one object dictionary; store/restore
#![cfg_attr(not(feature = "std"), no_std)]

extern crate alloc;
