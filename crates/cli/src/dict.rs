//! How the tool names objects: `drivebus_master::dict` (shared with the
//! Python package).

pub use drivebus_master::dict::*;
