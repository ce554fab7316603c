//! KC1 manufacturer objects acting as the manual says (issue 14): each
//! test names the section; the bodies are shared with the AKD
//! (`replay_rig/kc_objects.rs`).

mod replay_rig;
use drivebus_personality::Profile;
use replay_rig::kc_objects::{self as k, emcy};

const P: Profile = Profile::Kc1;

/// §7.2.1.3, §7.2.2.2, §7.2.2.3.
#[test]
fn status_register_and_faults() {
    k::status_register(P);
}

/// §6.4.4, §7.1 (n439 = FF12h), §7.2.2.1.
#[test]
fn warning_sends_emcy_and_bit7() {
    k::warning_n439(P);
}

/// §7.11.2.2; §7.1: F107 = 8580h.
#[test]
fn software_limit_after_save_and_restart() {
    k::software_limit_after_restart(P, emcy(0x8580, 0x80));
}

/// §7.7.2.1, §7.7.2.2.
#[test]
fn target_current_and_current_actual() {
    k::target_current(P);
}

/// §7.9.2.3.
#[test]
fn interpolation_period_whole_milliseconds() {
    k::ip_period_whole_ms(P);
}

/// §5.4 FBUS.PARAM02, §7.2.2.18.
#[test]
fn pll_locks_to_the_sync_period() {
    k::pll_lock(P);
}

/// §6.4.4.2, §7.1 (F129).
#[test]
fn heartbeat_loss_emcy_in_drive_form() {
    k::heartbeat_emcy_form(P);
}

/// §7.2.2.6, §8.1.3 (parameter names).
#[test]
fn ascii_channel_parameters() {
    k::ascii_parameters(P);
}

/// §7.2.1.18.
#[test]
fn os_prompt_one_character_at_a_time() {
    k::os_prompt(P);
}

/// §5.1.2 (motion tasks), §8.1.3 MT.*.
#[test]
fn motion_task_through_telnet() {
    k::motion_task(P);
}

/// §7.9.2.1: −1 is reserved; 0 and −2 are taken.
#[test]
fn interpolation_submode_reserved_refused() {
    let mut r = k::operational(P);
    assert_eq!(k::refused(&mut r, 0x60C0, 0, &(-1i16).to_le_bytes()), 0x0609_0030);
    k::put(&mut r, 0x60C0, 0, &(-2i16).to_le_bytes());
    k::put(&mut r, 0x60C0, 0, &0i16.to_le_bytes());
}

/// Object table mirrors of the measurements.
#[test]
fn measurement_mirrors() {
    k::measurement_mirrors(P);
}

/// VL.THRESH, F302.
#[test]
fn overspeed_fault() {
    k::overspeed(P);
}

/// MOTOR.TEMPWARN n301, MOTOR.TEMPFAULT F301.
#[test]
fn motor_temperature_warning_and_fault() {
    k::motor_temperature(P);
}

/// PL.ERRFTHRESH = 6065h.
#[test]
fn following_error_threshold() {
    k::following_error_threshold(P);
}

/// FBUS.PLLTHRESH.
#[test]
fn pll_lock_threshold() {
    k::pll_threshold(P);
}

/// FBUS.PARAM05 bit 0 and DRV.CLRFAULTS.
#[test]
fn fault_reset_by_telnet() {
    k::clear_faults_by_telnet(P);
}

/// MT.SET 3431h; MOTOR.IPEAK limits 2071h.
#[test]
fn motion_task_object_and_peak_current() {
    k::motion_task_object_and_peak_current(P);
}

/// DRV.DIR, MOTOR.VMAX, MT.TPOSWND, MT.TVELWND.
#[test]
fn drive_parameters() {
    k::drive_parameters(P);
}

/// pv scaling factor 204Ch with FBUS.PARAM05 bit 4.
#[test]
fn pv_scaling_factor() {
    k::pv_scaling(P);
}

/// MOTOR.ICONT scales 6071h/6077h/2077h.
#[test]
fn rated_current_scales_torque() {
    k::rated_current(P);
}

/// VBUS.UVFTHRESH, F502.
#[test]
fn under_voltage_fault() {
    k::under_voltage(P);
}

/// Latch objects over the touch probe.
#[test]
fn latch_objects() {
    k::latches(P);
}

/// DRV.ACC / DRV.DEC: the pv ramps while 6083h/6084h are 0.
#[test]
fn drive_ramps() {
    k::drive_ramps(P);
}

/// DRV.NVSAVE.
#[test]
fn nvsave_stores_parameters() {
    k::nvsave(P);
}

/// 345Ah brake control (0 → 1 → 3).
#[test]
fn brake_control_by_the_fieldbus() {
    k::brake_control(P);
}

/// MOTOR.BRAKERLS.
#[test]
fn brake_release_command() {
    k::brake_release_command(P);
}

/// AIN.VALUE.
#[test]
fn analog_input_value() {
    k::analog_input_value(P);
}

/// DIN1–7 in 60FDh, change flags, 20B8h; DOUT1/2.
#[test]
fn digital_inputs_and_outputs() {
    k::digital_io(P);
}

/// 60FEh bit 0 "set brake".
#[test]
fn set_brake_bit() {
    k::set_brake_bit(P);
}

/// DRV.HANDWHEEL, DRV.TEMPERATURES.
#[test]
fn secondary_feedback_and_ambient() {
    k::secondary_feedback(P);
}

/// n167: a pp target clamped to the software limit.
#[test]
fn pp_target_clamped_to_software_limit() {
    k::target_clamped_to_limit(P);
}
