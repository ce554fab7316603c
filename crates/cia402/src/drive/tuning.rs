//! A personality's tuning and motor objects on the running model: loop
//! gains and motor data ([`Drive::set_model_params`]), direction-dependent
//! current and speed limits, the I²t foldback
//! ([`crate::model::tuning`]). The machine's own values stay in
//! [`super::DriveConfig::params`] (what a parameter's "default" restores).

use super::Drive;
use crate::model::{DriveParams, FoldbackParams, ParamError};

impl Drive {
    /// Changes the motor, bus and control parameters of the running model
    /// ([`crate::model::DriveModel::set_params`]: the machine's encoder,
    /// axis and control rate stay).
    pub fn set_model_params(&mut self, p: DriveParams) -> Result<(), ParamError> {
        self.model.set_params(p)
    }

    /// Limits the current in the positive / negative direction \[A\]
    /// ([`crate::model::DriveModel::set_current_limits`]).
    pub fn set_current_limits(&mut self, positive: f64, negative: f64) -> Result<(), ParamError> {
        self.model.set_current_limits(positive, negative)
    }

    /// Limits the speed in the positive / negative direction \[rad/s\]
    /// ([`crate::model::DriveModel::set_velocity_limits`]).
    pub fn set_velocity_limits(&mut self, positive: f64, negative: f64) -> Result<(), ParamError> {
        self.model.set_velocity_limits(positive, negative)
    }

    /// The I²t foldback ([`crate::model::DriveModel::set_foldback`]).
    pub fn set_foldback(&mut self, p: Option<FoldbackParams>) -> Result<(), ParamError> {
        self.model.set_foldback(p)
    }

    /// A constant current offset and a friction compensation current \[A\]
    /// ([`crate::model::DriveModel::set_current_feedforward`]).
    pub fn set_current_feedforward(&mut self, offset: f64, friction: f64) -> Result<(), ParamError> {
        self.model.set_current_feedforward(offset, friction)
    }

    /// The largest voltage applied to the motor \[V\]
    /// ([`crate::model::DriveModel::set_voltage_limit`]).
    pub fn set_voltage_limit(&mut self, volts: f64) -> Result<(), ParamError> {
        self.model.set_voltage_limit(volts)
    }
}
