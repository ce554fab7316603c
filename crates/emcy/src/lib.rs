//! EMCY producer and consumer, error register and pre-defined error field (CiA 301 7.2.7)
#![cfg_attr(not(feature = "std"), no_std)]

extern crate alloc;
