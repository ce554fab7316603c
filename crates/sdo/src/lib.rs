//! SDO server and client (CiA 301 7.2.4): expedited, segmented and block transfer, sans-IO
#![cfg_attr(not(feature = "std"), no_std)]

extern crate alloc;
