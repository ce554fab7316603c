//! SYNC producer/consumer and TIME producer/consumer (CiA 301 7.2.5, 7.2.6)
#![cfg_attr(not(feature = "std"), no_std)]

extern crate alloc;
