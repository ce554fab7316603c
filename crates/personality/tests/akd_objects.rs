//! AKD manufacturer objects acting as the manual says (issue 14): each
//! test names the section; the bodies are shared with the KC1
//! (`replay_rig/kc_objects.rs`).

mod replay_rig;
use drivebus_personality::Profile;
use replay_rig::kc_objects::{self as k, emcy};
use replay_rig::kc_outputs as o;
use replay_rig::kc_tuning as t;

const P: Profile = Profile::Akd;

/// §6.2.1.3, §6.2.2.2, §6.2.2.3.
#[test]
fn status_register_and_faults() {
    k::status_register(P);
}

/// §5.4.4, §6.1 (n439 = FF12h), §6.2.2.1.
#[test]
fn warning_sends_emcy_and_bit7() {
    k::warning_n439(P);
}

/// §3.4 FBUS.PARAM05 bit 11: with it set, a warning sends no EMCY (bit 7
/// and 2000h still show it).
#[test]
fn warning_emcy_off_with_fbus_param05_bit11() {
    let mut r = k::operational(P);
    k::put(&mut r, 0x36E9, 0, &(1u32 << 11).to_le_bytes());
    k::put(&mut r, 0x3483, 0, &1i32.to_le_bytes());
    k::put(&mut r, 0x6083, 0, &3_600_000u32.to_le_bytes());
    k::put(&mut r, 0x6081, 0, &360_000u32.to_le_bytes());
    k::enable(&mut r, 1);
    r.take();
    k::put(&mut r, 0x607A, 0, &360_000i32.to_le_bytes());
    k::put(&mut r, 0x6040, 0, &0x1Fu16.to_le_bytes());
    let e = k::emcys_after(&mut r, 20);
    assert!(e.is_empty(), "no warning EMCY: {e:?}");
    assert_eq!(k::getu(&mut r, 0x2000, 1), 439);
    assert_ne!(r.statusword() & 0x80, 0);
}

/// §6.11.2.2; §6.1: n107 = 8582h (the AKD table has no F107).
#[test]
fn software_limit_after_save_and_restart() {
    k::software_limit_after_restart(P, emcy(0x8582, 0x80));
}

/// §6.7.2.1, §6.7.2.2.
#[test]
fn target_current_and_current_actual() {
    k::target_current(P);
}

/// §6.9.2.3.
#[test]
fn interpolation_period_whole_milliseconds() {
    k::ip_period_whole_ms(P);
}

/// §3.4 FBUS.PARAM02, §6.2.2.22.
#[test]
fn pll_locks_to_the_sync_period() {
    k::pll_lock(P);
}

/// §5.4.4.2, §6.1 (F129).
#[test]
fn heartbeat_loss_emcy_in_drive_form() {
    k::heartbeat_emcy_form(P);
}

/// §6.2.2.9, §7.1.4 (parameter names).
#[test]
fn ascii_channel_parameters() {
    k::ascii_parameters(P);
}

/// §6.2.1.19.
#[test]
fn os_prompt_one_character_at_a_time() {
    k::os_prompt(P);
}

/// §4.1 (motion tasks), §7.1.4 MT.*.
#[test]
fn motion_task_through_telnet() {
    k::motion_task(P);
}

/// §6.9.2.1: 0 only (linear interpolation).
#[test]
fn interpolation_submode_zero_only() {
    let mut r = k::operational(P);
    for m in [-1i16, -2] {
        assert_eq!(k::refused(&mut r, 0x60C0, 0, &m.to_le_bytes()), 0x0609_0030, "{m}");
    }
    k::put(&mut r, 0x60C0, 0, &0i16.to_le_bytes());
}

/// §7.1.5: the appendix lists 60C1h:2/3; they are read and written (the
/// linear interpolation does not use them).
#[test]
fn interpolation_record_subs_2_3_listed() {
    let mut r = k::operational(P);
    k::put(&mut r, 0x60C1, 2, &5u32.to_le_bytes());
    assert_eq!(k::getu(&mut r, 0x60C1, 2), 5);
    k::put(&mut r, 0x60C1, 3, &(-7i32).to_le_bytes());
    assert_eq!(k::get(&mut r, 0x60C1, 3), -7);
}

/// §6.2.2.4: DRV.RUNTIME in seconds.
#[test]
fn runtime_in_seconds() {
    let mut r = k::operational(P);
    r.run_ms(3000);
    assert_eq!(k::getu(&mut r, 0x2011, 0), 3);
}

/// §6.2.2.5, §6.2.2.6: the fault history, newest at sub 1, with its
/// DRV.RUNTIME time stamp.
#[test]
fn fault_history_numbers_and_times() {
    let mut r = k::operational(P);
    r.run_ms(2000);
    r.pn_mut().app.inject(drivebus_cia402::drive::Injection::Fault(0x8611));
    r.run_ms(10);
    k::put(&mut r, 0x6040, 0, &0x80u16.to_le_bytes());
    r.run_ms(1500);
    r.pn_mut().app.inject(drivebus_cia402::drive::Injection::Fault(0x4310));
    r.run_ms(10);
    assert_eq!(k::getu(&mut r, 0x2012, 1), 235, "F235 newest");
    assert_eq!(k::getu(&mut r, 0x2012, 2), 439, "F439 before");
    assert_eq!(k::getu(&mut r, 0x2013, 1), 3);
    assert_eq!(k::getu(&mut r, 0x2013, 2), 2);
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

/// B.4 (2014h–2017h): a TPDO change mask keeps masked statusword changes
/// from sending the event-driven TPDO1.
#[test]
fn tpdo_change_mask() {
    let mut r = k::operational(P);
    let tpdo1_after = |r: &mut replay_rig::Rig, cw: u16| {
        let [lo, hi] = cw.to_le_bytes();
        r.take();
        r.send(&format!("603#2B406000{lo:02X}{hi:02X}0000"));
        r.run_ms(10);
        r.take().iter().filter(|f| f.std_id() == Some(0x183)).count()
    };
    assert_eq!(tpdo1_after(&mut r, 0x06), 1, "default mask: every change");
    k::put(&mut r, 0x2014, 1, &0u32.to_le_bytes());
    k::put(&mut r, 0x2014, 2, &0u32.to_le_bytes());
    assert_eq!(tpdo1_after(&mut r, 0x07), 0, "nothing monitored");
    k::put(&mut r, 0x2014, 1, &4u32.to_le_bytes());
    assert_eq!(tpdo1_after(&mut r, 0x06), 0, "bit 2 unchanged");
    assert_eq!(tpdo1_after(&mut r, 0x0F), 1, "bit 2 set");
}

/// §3.4 FBUS.PARAM04 = 1: SYNC loss after the first SYNC is F125 (EMCY
/// 8780h); 0 leaves it unsupervised.
#[test]
fn sync_supervision_fbus_param04() {
    for on in [0u32, 1] {
        let mut r = k::operational(P);
        k::put(&mut r, 0x36E8, 0, &on.to_le_bytes());
        k::put(&mut r, 0x1006, 0, &1000u32.to_le_bytes());
        k::syncs(&mut r, 1000, 5);
        let e = k::emcys_after(&mut r, 20);
        if on == 0 {
            assert!(e.is_empty(), "{e:?}");
        } else {
            assert_eq!(e.first(), Some(&emcy(0x8780, 0x80)), "F125");
            assert_eq!(k::getu(&mut r, 0x2001, 1), 125);
        }
    }
}

/// §7.1.5 (608Fh:1 RW): encoder increments, powers of 2 only.
#[test]
fn encoder_resolution_powers_of_two() {
    let mut r = k::operational(P);
    k::put(&mut r, 0x608F, 1, &0x0010_0000u32.to_le_bytes());
    assert_eq!(k::getu(&mut r, 0x608F, 1), 0x0010_0000);
    assert_eq!(k::refused(&mut r, 0x608F, 1, &3000u32.to_le_bytes()), 0x0609_0030);
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

/// `P` on its default machine, NMT operational, with analog input 1 at
/// `volts` and the master encoder at `master` counts/s.
fn with_inputs(volts: f64, master: f64) -> replay_rig::Rig {
    use drivebus_cia402::drive::Injection;
    use drivebus_cia402::model::ModelInjection as Plant;
    let m = drivebus_personality::machine::Machine::default_for(P);
    let (mut r, _) = replay_rig::Rig::with(P.build_on(k::ID, &m).unwrap());
    r.pn_mut().app.inject(Injection::Model(Plant::AnalogInput { channel: 1, volts }));
    r.pn_mut().app.inject(Injection::Model(Plant::MasterVelocity(master)));
    r.send("000#0103");
    r.run_ms(5);
    r
}

/// §6.4.2.4 mode −2: analog velocity, analog input 1 (2.5 V, less
/// AIN.OFFSET 0.5 V) × AIN.VSCALE (10 rpm/V) = 20 rpm = 12000 units/s;
/// AIN.VALUE 3509h reads the input (mV); inside AIN.DEADBAND nothing moves.
#[test]
fn mode_minus_2_analog_velocity() {
    let mut r = with_inputs(2.5, 0.0);
    assert_eq!(k::get(&mut r, 0x3509, 0), 2500, "AIN.VALUE mV");
    k::put(&mut r, 0x3629, 0, &10_000i32.to_le_bytes());
    k::put(&mut r, 0x5003, 0, &500u32.to_le_bytes());
    k::enable(&mut r, -2);
    r.run_ms(1000);
    let v = k::get(&mut r, 0x606C, 0);
    assert!((v - 12_000).abs() < 300, "20 rpm: {v}");
    k::put(&mut r, 0x5001, 0, &2500u32.to_le_bytes());
    r.run_ms(1000);
    assert!(k::get(&mut r, 0x606C, 0).abs() < 300, "inside the deadband");
}

/// Mode −1: analog current, 2 V × AIN.ISCALE 250 mA/V = 500 mA (6071h =
/// 500 mA in per mille of the rated current); 2077h reads it.
#[test]
fn mode_minus_1_analog_current() {
    let mut r = with_inputs(2.0, 0.0);
    k::put(&mut r, 0x5002, 0, &250u32.to_le_bytes());
    k::enable(&mut r, -1);
    r.run_ms(30);
    let i = k::get(&mut r, 0x2077, 0);
    assert!((i - 500).abs() < 60, "500 mA: {i}");
    assert!(k::get(&mut r, 0x606C, 0) > 0, "the motor accelerates");
}

/// Mode −3: electronic gearing, the master encoder at 2^19 counts/s ×
/// GEAR.OUT/GEAR.IN = 1/2 → 2^18 increments/s = 1/4 rev/s = 9000 units/s.
#[test]
fn mode_minus_3_gearing() {
    let mut r = with_inputs(0.0, f64::from(1u32 << 19));
    k::put(&mut r, 0x50BE, 0, &1u32.to_le_bytes());
    k::put(&mut r, 0x50BB, 0, &2u32.to_le_bytes());
    k::enable(&mut r, -3);
    r.run_ms(1000);
    let v = k::get(&mut r, 0x606C, 0);
    assert!((v - 9_000).abs() < 300, "geared: {v}");
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

/// DRV.HANDWHEEL, DRV.TEMPERATURES; §6.5.4: 60E4h:1 is the secondary
/// feedback in user units through 60E8h/60EDh (gear) and 60E9h/60EEh
/// (feed), one revolution = FB2.ENCRES counts (0: the primary's 2^20).
#[test]
fn secondary_feedback_and_additional_position() {
    let mut r = k::secondary_feedback(P);
    assert_eq!(k::get(&mut r, 0x60E4, 1), 1, "one revolution, feed 1");
    k::put(&mut r, 0x60E9, 1, &36_000u32.to_le_bytes());
    k::put(&mut r, 0x60E8, 1, &2u32.to_le_bytes());
    r.run_ms(1);
    assert_eq!(k::get(&mut r, 0x60E4, 1), 18_000, "gear 2:1, feed 36000");
    k::put(&mut r, 0x51EC, 0, &(1u32 << 19).to_le_bytes());
    r.run_ms(1);
    assert_eq!(k::get(&mut r, 0x60E4, 1), 36_000, "FB2.ENCRES 2^19: two revolutions");
}

/// n167: a pp target clamped to the software limit.
#[test]
fn pp_target_clamped_to_software_limit() {
    k::target_clamped_to_limit(P);
}

/// A warning whose EMCY went out before FBUS.PARAM05 bit 11 was set still
/// sends its reset EMCY when it goes (1001h back to 0).
#[test]
fn warning_reset_emcy_after_bit11_set() {
    let mut r = k::operational(P);
    k::put(&mut r, 0x3453, 0, &1u32.to_le_bytes());
    assert_eq!(k::emcys_after(&mut r, 5), vec![emcy(0x7186, 0x80)], "n301");
    k::put(&mut r, 0x36E9, 0, &(1u32 << 11).to_le_bytes());
    k::put(&mut r, 0x3453, 0, &0u32.to_le_bytes());
    let e = k::emcys_after(&mut r, 5);
    // The error-reset EMCY: code 0000h, register 00h, bytes 3–7 zero.
    assert_eq!(e, vec![drivebus_can::Frame::new(0x83, &[0; 8])], "reset EMCY");
    assert_eq!(k::getu(&mut r, 0x1001, 0), 0);
}

/// §7.1.4: PL.KP 3542h.
#[test]
fn position_loop_gain() {
    t::position_gain(P);
}

/// §7.1.4: VL.KVFF 354Bh, 3407h:2.
#[test]
fn velocity_feedforward_share() {
    t::velocity_feedforward(P);
}

/// §7.1.4: VL.KP 3548h.
#[test]
fn velocity_loop_gain() {
    t::velocity_gain(P);
}

/// §7.1.4: VL.KI 354Dh.
#[test]
fn velocity_loop_integral() {
    t::velocity_integral(P);
}

/// §7.1.4: MOTOR.INERTIA 35ABh, LOAD.INERTIA 525Fh.
#[test]
fn motor_and_load_inertia() {
    t::inertia(P);
}

/// §7.1.4: MOTOR.KT 3593h.
#[test]
fn motor_torque_constant() {
    t::torque_constant(P);
}

/// §7.1.4: MOTOR.R 3456h.
#[test]
fn motor_winding_resistance() {
    t::winding_resistance(P);
}

/// §7.1.4: MOTOR.KE 5260h.
#[test]
fn motor_back_emf_constant() {
    t::back_emf(P);
}

/// §7.1.4: IL.LIMITP 356Eh, IL.LIMITN 356Fh, 60E0h/60E1h (§6.7.2.7/8).
#[test]
fn current_limits_per_direction() {
    t::current_limits(P);
}

/// §7.1.4: VL.LIMITP 3622h, VL.LIMITN 3623h.
#[test]
fn velocity_limits_per_direction() {
    t::velocity_limits(P);
}

/// §7.1.4: MOTOR.CTF0, IL.IFOLD, IL.MIFOLD, IL.MI2T, IL.FOLDWTHRESH (n304), IL.FOLDFTHRESHU (F304); §6.1 F304/n304.
#[test]
fn motor_foldback() {
    t::foldback(P);
}

/// §7.1.4: PLS.P/WIDTH/T/EN/MODE/RESET/STATE 34A0h–34A3h.
#[test]
fn position_limit_switches() {
    o::position_limit_switches(P);
}

/// §7.1.4: MOTOR.TBRAKERLS 366Fh, MOTOR.TBRAKEAPP 366Eh.
#[test]
fn brake_times() {
    o::brake_times(P);
}

/// §7.1.4: VL.FBFILTER 3407h:1.
#[test]
fn filtered_speed() {
    o::filtered_speed(P);
}

/// §7.1.4: IL.OFFSET 3423h, IL.FRICTION 3422h.
#[test]
fn current_feedforward() {
    t::current_feedforward(P);
}

/// §7.1.4: IL.KP 3598h, MOTOR.LQLL 3455h.
#[test]
fn current_loop_gain() {
    t::current_loop_gain(P);
}

/// §7.1.4: AOUT.VALUEU 3470h:3, AOUT.VALUE 3470h:2.
#[test]
fn analog_output() {
    o::analog_output(P);
}

/// §7.1.4: AIN.CUTOFF 5000h.
#[test]
fn analog_input_cutoff() {
    o::analog_input_cutoff(P);
}

/// §7.1.4 AIN.CUTOFF 5000h in mode −1: the current set-point follows the
/// filtered analog input (2 V × 250 mA/V, 1 Hz: τ ≈ 159 ms, a fifth of
/// the way after 35 ms) where without the filter it is there at once.
#[test]
fn mode_minus_1_follows_the_filtered_input() {
    use drivebus_cia402::drive::Injection;
    use drivebus_cia402::model::ModelInjection as Plant;
    let current = |cutoff: u32| {
        let mut r = with_inputs(0.0, 0.0);
        k::put(&mut r, 0x5002, 0, &250u32.to_le_bytes());
        k::put(&mut r, 0x5000, 0, &cutoff.to_le_bytes());
        k::enable(&mut r, -1);
        r.pn_mut().app.inject(Injection::Model(Plant::AnalogInput { channel: 1, volts: 2.0 }));
        r.run_ms(35);
        k::get(&mut r, 0x2077, 0)
    };
    let (raw, filtered) = (current(0), current(1));
    assert!((raw - 500).abs() < 60, "unfiltered: {raw} mA");
    assert!((60..=140).contains(&filtered), "1 Hz: {filtered} mA");
}

/// §7.1.4: MOTOR.VOLTMAX 3452h.
#[test]
fn motor_voltage() {
    t::motor_voltage(P);
}

/// §7.1.4: REGEN.POWER 3416h.
#[test]
fn regen_power() {
    t::regen_power(P);
}

/// §7.1.4, §6.2.1.3: HOME.SET 35F0h.
#[test]
fn home_set() {
    o::home_set(P);
}

/// §7.1.4: FB1.OFFSET 3490h.
#[test]
fn position_offset() {
    o::position_offset(P);
}
