//! The machine's signals (`docs/machine.md` "Inputs, outputs, brake,
//! temperature"): the machine file's keys and their errors, and the
//! generic drive on the virtual bus with them — 60FDh bits 16–31 from the
//! input lines, 60FEh:1 driving output lines wired back, the holding
//! brake's sequence on enable/disable with a hanging load (CiA 402-2
//! 60FEh bit 0 "set brake"), input changes and a hot motor on the
//! schedule, the master encoder.

mod replay_rig;

use drivebus_personality::Profile;
use drivebus_personality::machine::{Brake, Input, InputChange, Machine, MachineFile};
use replay_rig::Rig;

const SIGNALS: &str = r#"
[[node]]
id = 5

[node.io]
digital_inputs = [2, 16]
analog_inputs = [1.5, -2.0]
wiring = { 1 = 5, 3 = 16 }

[node.master_encoder]
position = 100.0
velocity = 2000.0

[node.brake]
release_delay = 0.05
apply_delay = 0.04
holding_torque = 3.0

[node.temperature]
ambient = 30.0
motor = 45.0

[[node.inputs]]
at = 0.1
input = "digital"
line = 3
value = 1
duration = 0.1

[[node.inputs]]
at = 0.2
input = "master_position"
value = -500

[[node.inputs]]
at = 0.3
input = "analog"
line = 4
value = 9.5
"#;

#[test]
fn the_signals_keys_parse() {
    let f = MachineFile::parse(SIGNALS).unwrap();
    let m = f.machine_for(Profile::Generic, 5).unwrap();
    assert_eq!(m.io.digital_inputs, 1 << 1 | 1 << 15);
    assert_eq!(m.io.analog_inputs, [1.5, -2.0, 0.0, 0.0]);
    assert_eq!((m.io.wiring[0], m.io.wiring[2], m.io.wiring[1]), (5, 16, 0));
    assert_eq!((m.master_encoder.position, m.master_encoder.velocity), (100.0, 2000.0));
    assert_eq!(m.brake, Some(Brake { release_delay: 0.05, apply_delay: 0.04, holding_torque: Some(3.0) }));
    assert_eq!((m.temperature.ambient, m.temperature.motor), (Some(30.0), Some(45.0)));
    assert_eq!(
        m.inputs,
        [
            InputChange { at: 0.1, input: Input::Digital { line: 3, level: true }, duration: Some(0.1) },
            InputChange { at: 0.2, input: Input::MasterPosition(-500.0), duration: None },
            InputChange { at: 0.3, input: Input::Analog { channel: 4, volts: 9.5 }, duration: None },
        ]
    );
    // Into the model: the brake's torque reflected (direct drive), the
    // ambient the motor starts at.
    let dev = Profile::Generic.build_on(5, &m).unwrap();
    let p = dev.app.drive.model().params();
    assert_eq!(p.io.brake.map(|b| b.holding_torque), Some(3.0));
    assert_eq!(p.motor.ambient_temperature, 30.0);
    assert_eq!(dev.app.drive.model().temperature(), 45.0);
    // The default machines have none of it.
    let d = Machine::default_for(Profile::Generic);
    assert_eq!((d.brake, d.io.digital_inputs, d.inputs.len()), (None, 0, 0));
    // `enabled = false` takes the brake off again; a brake without a
    // holding torque holds twice the motor's peak.
    let off = MachineFile::parse("[[node]]\nid = 5\nbrake = { enabled = false }\n").unwrap();
    assert_eq!(off.machine_for(Profile::Generic, 5).unwrap().brake, None);
    let m = Machine {
        brake: Some(Brake { release_delay: 0.0, apply_delay: 0.0, holding_torque: None }),
        gear_ratio: 2.0,
        ..Machine::default()
    };
    let dev = Profile::Generic.build_on(5, &m).unwrap();
    let motor = dev.app.drive.model().params().motor;
    let held = dev.app.drive.model().params().io.brake.unwrap().holding_torque;
    assert_eq!(held, 2.0 * motor.kt * motor.max_current);
}

/// Node 5's error: line, column, message.
fn error(text: &str) -> (usize, usize, String) {
    let e = match MachineFile::parse(text) {
        Err(e) => e,
        Ok(f) => f.machine_for(Profile::Generic, 5).expect_err("an error"),
    };
    (e.line, e.column, e.message)
}

#[test]
fn malformed_signals_name_their_place() {
    let node = "[[node]]\nid = 5\n";
    let cases: &[(&str, (usize, usize), &str)] = &[
        ("[node.io]\ndigital_inputs = [1, 17]\n", (4, 22), "io.digital_inputs: 17 is not a line in 1..=16"),
        ("[node.io]\ndigital_inputs = [0]\n", (4, 19), "is not a line"),
        ("[node.io]\nanalog_inputs = [1, 2, 3, 4, 5]\n", (4, 17), "at most 4 channels"),
        ("[node.io]\nanalog_inputs = [1e6]\n", (4, 17), "io.analog_inputs: 1000000 is not a voltage"),
        ("[node.io]\nwiring = { 17 = 1 }\n", (4, 17), "io.wiring: output 17 is not a line"),
        ("[node.io]\nwiring = { x = 1 }\n", (4, 16), "io.wiring: output x"),
        ("[node.io]\nwiring = { 1 = 0 }\n", (4, 16), "io.wiring: input 0 is not a line"),
        ("[node.io]\ndigital = [1]\n", (4, 1), "unknown field `digital`"),
        ("[node.master_encoder]\nvelocity = inf\n", (4, 12), "master_encoder.velocity: inf is not a number"),
        ("[node.brake]\nrelease_delay = 0.1\n", (4, 17), "brake.apply_delay: missing"),
        ("[node.brake]\nrelease_delay = -0.1\napply_delay = 0\n", (4, 17), "must not be negative"),
        ("[node.brake]\nrelease_delay = 0\napply_delay = 5000\n", (5, 15), "more than 1000 s"),
        ("[node.brake]\nrelease_delay = 0\napply_delay = 0\nholding_torque = -1\n", (6, 18), "negative"),
        ("[node.temperature]\nambient = 90\n", (4, 11), "temperature.ambient: 90 is not a temperature"),
        ("[node.temperature]\nmotor = \"hot\"\n", (4, 9), "invalid type"),
        ("[[node.inputs]]\nat = 1\ninput = \"pressure\"\nvalue = 1\n", (5, 9), "pressure"),
        (
            "[[node.inputs]]\nat = 1\ninput = \"digital\"\nvalue = 1\n",
            (5, 9),
            "inputs[0].input: needs `line`",
        ),
        (
            "[[node.inputs]]\nat = 1\ninput = \"brake\"\nline = 2\nvalue = 1\n",
            (6, 8),
            "inputs[0].line: only `digital` and `analog` take a line",
        ),
        (
            "[[node.inputs]]\nat = 1\ninput = \"digital\"\nline = 3\nvalue = 2\n",
            (7, 9),
            "not a level (0 or 1)",
        ),
        (
            "[[node.inputs]]\nat = 1\ninput = \"digital\"\nline = 17\nvalue = 1\n",
            (6, 8),
            "inputs[0].line: 17",
        ),
        ("[[node.inputs]]\nat = 1\ninput = \"analog\"\nline = 5\nvalue = 1\n", (6, 8), "not an analog input"),
        ("[[node.inputs]]\nat = 1\ninput = \"analog\"\nline = 1\nvalue = 2e3\n", (7, 9), "inputs[0].value"),
        ("[[node.inputs]]\nat = -1\ninput = \"brake\"\nvalue = 1\n", (4, 6), "inputs[0].at"),
        (
            "[[node.inputs]]\nat = 1\ninput = \"master_position\"\nvalue = 1\nduration = 1\n",
            (7, 12),
            "inputs[0].duration: a master_position change is a jump",
        ),
        ("[[node.inputs]]\nat = 1\ninput = \"motor_temperature\"\nvalue = 900\n", (6, 9), "inputs[0].value"),
        ("[[node.inputs]]\nat = 1\ninput = \"brake\"\n", (3, 1), "missing field `value`"),
    ];
    for (text, place, message) in cases {
        let (l, c, m) = error(&format!("{node}{text}"));
        assert_eq!((l, c), *place, "{text:?}: {m}");
        assert!(m.contains(message), "{text:?}: {m}");
    }
}

const NODE: u8 = 5;

fn rig(m: &Machine) -> Rig {
    let (r, _) = Rig::with(Profile::Generic.build_on(NODE, m).unwrap());
    r
}

/// Position actual value 6064h \[position units\].
fn position(r: &mut Rig) -> i32 {
    r.read_u32(NODE, 0x6064, 0) as i32
}

fn controlword(r: &mut Rig, cw: u16) {
    assert_eq!(r.download(NODE, 0x6040, 0, &cw.to_le_bytes()), Ok(()));
}

fn statusword(r: &mut Rig) -> u16 {
    r.read_u32(NODE, 0x6041, 0) as u16
}

#[test]
fn generic_input_lines_and_wired_outputs_in_60fd_and_60fe() {
    let m = MachineFile::parse(SIGNALS).unwrap().machine_for(Profile::Generic, 5).unwrap();
    let mut r = rig(&m);
    // Lines 2 and 16 high: 60FDh bits 17 and 31 (CiA 402-2: bits 16–31
    // manufacturer-specific), the switches below untouched.
    assert_eq!(r.read_u32(NODE, 0x60FD, 0), 1 << 17 | 1 << 31);
    // 60FEh:1 bit 16 = output line 1, wired to input 5 (bit 20).
    assert_eq!(r.download(NODE, 0x60FE, 1, &(1u32 << 16).to_le_bytes()), Ok(()));
    assert_eq!(r.pn().app.drive.output_lines(), 1);
    r.run_ms(1);
    assert_eq!(r.read_u32(NODE, 0x60FD, 0), 1 << 17 | 1 << 20 | 1 << 31);
    // The mask (60FEh:2) takes output line 1 away: the input drops.
    assert_eq!(r.download(NODE, 0x60FE, 2, &0xFFFE_0000u32.to_le_bytes()), Ok(()));
    assert_eq!(r.download(NODE, 0x60FE, 1, &(1u32 << 16).to_le_bytes()), Ok(()));
    r.run_ms(1);
    assert_eq!(r.read_u32(NODE, 0x60FD, 0), 1 << 17 | 1 << 31);
    // A personality's output object drives the same lines.
    r.pn_mut().app.drive.set_output_lines(1 << 2);
    r.run_ms(1);
    assert_eq!(r.read_u32(NODE, 0x60FD, 0), 1 << 17 | 1 << 31, "output 3 drives input 16, already high");
    r.pn_mut().app.drive.set_output_lines(1);
    r.run_ms(1);
    assert_eq!(r.read_u32(NODE, 0x60FD, 0) >> 16, 1 << 1 | 1 << 4 | 1 << 15);
    // The schedule: line 3 high from 0.1 s for 0.1 s, then back to the
    // machine's levels.
    let t = r.now().as_nanos();
    r.run_ms(150 - (t / 1_000_000));
    assert_eq!(r.read_u32(NODE, 0x60FD, 0) >> 16, 1 << 1 | 1 << 2 | 1 << 4 | 1 << 15);
    r.run_ms(100);
    assert_eq!(r.read_u32(NODE, 0x60FD, 0) >> 16, 1 << 1 | 1 << 4 | 1 << 15);
    // Analog 4 at 0.3 s, the master encoder jumped at 0.2 s and runs at
    // 2000 counts/s.
    r.run_ms(100);
    let model = r.pn().app.drive.model();
    assert_eq!((model.analog_input(1), model.analog_input(4)), (1.5, 9.5));
    let (t, p) = (r.now().as_nanos() as f64 / 1e9, model.master_position());
    assert!((p - (-500 + ((t - 0.2) * 2000.0) as i64)).abs() <= 2, "{p} at {t} s");
    assert_eq!(model.master_velocity(), 2000.0);
}

/// The generic servo on a vertical axis: 0.3 N·m of gravity pulling
/// negative at the motor (direct drive), a brake releasing in 50 ms and
/// applying in 40 ms, profile position mode.
fn hanging() -> Machine {
    let mut m = Machine {
        brake: Some(Brake { release_delay: 0.05, apply_delay: 0.04, holding_torque: None }),
        ..Machine::default()
    };
    m.load.torque = -0.3;
    m
}

#[test]
fn generic_brake_sequence_holds_a_hanging_load() {
    let mut r = rig(&hanging());
    r.run_ms(200);
    let p0 = position(&mut r);
    assert_eq!(p0, 0, "the brake holds the load with the power stage off");
    assert!(r.pn().app.drive.model().brake().engaged);
    // pp: a move of 10 degrees (generic: 1000 units per degree).
    assert_eq!(r.download(NODE, 0x6060, 0, &[1]), Ok(()));
    assert_eq!(r.download(NODE, 0x607A, 0, &10_000i32.to_le_bytes()), Ok(()));
    controlword(&mut r, 0x06);
    controlword(&mut r, 0x07);
    controlword(&mut r, 0x0F);
    controlword(&mut r, 0x1F);
    assert_eq!(statusword(&mut r) & 0x6F, 0x27, "operation enabled at once");
    r.run_ms(1);
    let b = r.pn().app.drive.model().brake();
    assert!(b.engaged && !b.commanded && b.pending, "releasing: {b:?}");
    // Within the release delay the set-point waits: no motion, no
    // acknowledge yet.
    r.run_ms(39);
    assert_eq!(position(&mut r), p0);
    assert_eq!(statusword(&mut r) & 0x1000, 0, "set-point not yet taken");
    assert!(r.pn().app.drive.model().brake().engaged);
    // Released after 50 ms, the move runs and ends at the target.
    r.run_ms(20);
    assert!(!r.pn().app.drive.model().brake().engaged);
    r.run_ms(500);
    assert!((position(&mut r) - 10_000).abs() <= 20, "{}", position(&mut r));
    controlword(&mut r, 0x0F);
    // Shutdown (605Bh 0: the drive function off at once): the power stage
    // holds through the apply delay, the load does not drop.
    let at = position(&mut r);
    controlword(&mut r, 0x06);
    assert_eq!(statusword(&mut r) & 0x6F, 0x21, "ready to switch on");
    r.run_ms(1);
    let b = r.pn().app.drive.model().brake();
    assert!(!b.engaged && b.commanded && b.pending, "applying: {b:?}");
    r.run_ms(29);
    assert!(r.pn().app.drive.model().demand() != drivebus_cia402::model::Demand::Off);
    r.run_ms(20);
    assert_eq!(r.pn().app.drive.model().demand(), drivebus_cia402::model::Demand::Off);
    assert!(r.pn().app.drive.model().brake().engaged);
    r.run_ms(500);
    assert!((position(&mut r) - at).abs() <= 20, "held: {} from {at}", position(&mut r));
}

#[test]
fn generic_set_brake_bit_and_a_released_brake_let_the_load_fall() {
    let mut r = rig(&hanging());
    // 60FEh:1 bit 0 "set brake" needs 60FEh:2 bit 0.
    assert_eq!(r.download(NODE, 0x60FE, 2, &0xFFFF_0001u32.to_le_bytes()), Ok(()));
    assert_eq!(r.download(NODE, 0x6060, 0, &[3]), Ok(()));
    for cw in [0x06u16, 0x07, 0x0F] {
        controlword(&mut r, cw);
    }
    r.run_ms(100);
    assert!(!r.pn().app.drive.model().brake().engaged);
    assert_eq!(r.download(NODE, 0x60FE, 1, &1u32.to_le_bytes()), Ok(()));
    r.run_ms(50);
    let b = r.pn().app.drive.model().brake();
    assert!(b.commanded && b.engaged, "set brake: {b:?}");
    assert_eq!(r.download(NODE, 0x60FE, 1, &0u32.to_le_bytes()), Ok(()));
    r.run_ms(60);
    assert!(!r.pn().app.drive.model().brake().engaged);
    // Disable voltage, and a brake held released (a manual release lever
    // on the machine's schedule): nothing holds the load.
    controlword(&mut r, 0x00);
    r.pn_mut().app.inject(drivebus_cia402::drive::Injection::Model(
        drivebus_cia402::model::ModelInjection::Brake(Some(false)),
    ));
    let at = position(&mut r);
    r.run_ms(100);
    assert!(position(&mut r) < at - 1000, "the load falls: {} from {at}", position(&mut r));
}

#[test]
fn generic_hot_motor_faults_on_the_schedule() {
    let mut m = Machine::default();
    m.temperature.motor = Some(60.0);
    m.inputs.push(InputChange { at: 0.2, input: Input::MotorTemperature(130.0), duration: Some(0.1) });
    let mut r = rig(&m);
    r.run_ms(100);
    assert_eq!(r.pn().app.drive.model().temperature(), 60.0);
    assert_eq!(statusword(&mut r) & 0x4F, 0x40);
    r.take();
    r.run_ms(150);
    // Over the motor's 120 °C: fault 4310h with its EMCY.
    assert_eq!(statusword(&mut r) & 0x4F, 0x08);
    assert_eq!(r.read_u32(NODE, 0x603F, 0) & 0xFFFF, 0x4310);
    // Cool again after 0.1 s: the machine's 60 °C, and a fault reset clears.
    r.run_ms(100);
    assert_eq!(r.pn().app.drive.model().temperature(), 60.0);
    controlword(&mut r, 0x80);
    r.run_ms(1);
    assert_eq!(statusword(&mut r) & 0x4F, 0x40);
}
