//! LSS slave and master frame codecs (CiA 305), sans-IO
#![cfg_attr(not(feature = "std"), no_std)]

extern crate alloc;
