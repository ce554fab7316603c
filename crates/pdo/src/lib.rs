//! PDO service (CiA 301 7.2.2): RPDO/TPDO communication and mapping, sans-IO
#![cfg_attr(not(feature = "std"), no_std)]

extern crate alloc;
