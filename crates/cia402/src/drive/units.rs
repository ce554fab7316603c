//! Factor group (CiA 402-2 §6.4 / IEC 61800-7-201 "factor group"): user
//! position, velocity and acceleration units ↔ encoder increments, in exact
//! rational arithmetic.
//!
//! increments per position unit = (608Fh:1 / 608Fh:2) · (6091h:1 / 6091h:2)
//! / (6092h:1 / 6092h:2): encoder increments per motor revolution, times
//! motor revolutions per driving-shaft revolution, divided by feed per
//! driving-shaft revolution. The product of three `u32` ratios fits `u128`
//! numerators and denominators, reduced by their gcd; conversions multiply
//! in `i128`, so no move ever loses an increment ([`Carry`] carries the
//! remainder of relative conversions).

use core::f64::consts::PI;

/// A reduced positive fraction.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Ratio {
    /// Numerator (> 0).
    pub num: u128,
    /// Denominator (> 0).
    pub den: u128,
}

const fn gcd(mut a: u128, mut b: u128) -> u128 {
    while b != 0 {
        let t = a % b;
        a = b;
        b = t;
    }
    a
}

impl Ratio {
    /// `1/1`.
    pub const ONE: Ratio = Ratio { num: 1, den: 1 };

    /// `num / den` reduced; `None` if either is zero.
    pub const fn new(num: u128, den: u128) -> Option<Ratio> {
        if num == 0 || den == 0 {
            return None;
        }
        let g = gcd(num, den);
        Some(Ratio { num: num / g, den: den / g })
    }

    /// Product of two ratios, reduced; `None` on overflow.
    pub fn times(self, o: Ratio) -> Option<Ratio> {
        // Cross-reduce first so products of u32 chains never overflow.
        let g1 = gcd(self.num, o.den);
        let g2 = gcd(o.num, self.den);
        let n = (self.num / g1).checked_mul(o.num / g2)?;
        let d = (self.den / g2).checked_mul(o.den / g1)?;
        Ratio::new(n, d)
    }

    /// The reciprocal.
    pub const fn inv(self) -> Ratio {
        Ratio { num: self.den, den: self.num }
    }

    /// As a float.
    pub fn to_f64(self) -> f64 {
        self.num as f64 / self.den as f64
    }

    /// `round(x · num / den)` (half away from zero), saturating to `i64`.
    pub fn apply_round(self, x: i64) -> i64 {
        let p = i128::from(x).saturating_mul(self.num as i128);
        let d = self.den as i128;
        let q = if p >= 0 { (p + d / 2) / d } else { -((-p + d / 2) / d) };
        q.clamp(i128::from(i64::MIN), i128::from(i64::MAX)) as i64
    }
}

/// The factor group values as written in the object dictionary.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct FactorGroup {
    /// 608Fh:1 encoder increments, 608Fh:2 motor revolutions.
    pub encoder: (u32, u32),
    /// 6090h:1 velocity encoder increments per second, :2 motor revolutions per second.
    pub velocity_encoder: (u32, u32),
    /// 6091h:1 motor revolutions, :2 driving shaft revolutions.
    pub gear: (u32, u32),
    /// 6092h:1 feed, :2 driving shaft revolutions.
    pub feed: (u32, u32),
    /// 6096h:1/:2 velocity factor: position units per second per velocity unit.
    pub velocity_factor: (u32, u32),
    /// 6097h:1/:2 acceleration factor: position units per second² per acceleration unit.
    pub acceleration_factor: (u32, u32),
    /// 607Eh polarity: bit 7 position, bit 6 velocity.
    pub polarity: u8,
    /// Scaling objects in force instead of the chain above (DSP 402 v2
    /// 6093h/6094h, Technosoft iPOS §5.2): `None` for CiA 402-2's chain.
    /// With it, 6091h/6092h/6096h/6097h are stored set-up values only.
    pub scaling: Option<Scaling>,
}

/// Direct scaling of user units to the drive's internal units (the
/// "factor" objects of DSP 402 v2: internal = user · num / div), and what
/// one internal velocity and acceleration unit is. Technosoft iPOS §5.2:
/// 6093h position factor, 6094h velocity encoder factor, 210Fh
/// acceleration encoder factor; internal velocity = increments per 1 ms
/// sample in 16.16, internal acceleration = increments per sample² in 16.16.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Scaling {
    /// Increments per position unit (6093h:1 / 6093h:2).
    pub position: (u32, u32),
    /// Internal velocity units per velocity unit (6094h:1 / 6094h:2).
    pub velocity: (u32, u32),
    /// Internal acceleration units per acceleration unit.
    pub acceleration: (u32, u32),
    /// Increments/s per internal velocity unit.
    pub velocity_unit: (u32, u32),
    /// Increments/s² per internal acceleration unit.
    pub acceleration_unit: (u32, u32),
}

impl Scaling {
    /// 1/1 factors over internal units of `velocity_unit` increments/s and
    /// `acceleration_unit` increments/s².
    pub const fn unit(velocity_unit: (u32, u32), acceleration_unit: (u32, u32)) -> Self {
        Scaling { position: (1, 1), velocity: (1, 1), acceleration: (1, 1), velocity_unit, acceleration_unit }
    }

    /// (increments per position unit, position units/s per velocity unit,
    /// position units/s² per acceleration unit); `None` on a zero term.
    fn ratios(&self) -> Option<(Ratio, Ratio, Ratio)> {
        let pos = ratio(self.position)?;
        let vel = ratio(self.velocity)?.times(ratio(self.velocity_unit)?)?.times(pos.inv())?;
        let acc = ratio(self.acceleration)?.times(ratio(self.acceleration_unit)?)?.times(pos.inv())?;
        Some((pos, vel, acc))
    }
}

impl FactorGroup {
    /// Increments = position units, velocity units = position units/s.
    pub const fn increments(counts_per_rev: u32) -> Self {
        FactorGroup {
            encoder: (counts_per_rev, 1),
            velocity_encoder: (counts_per_rev, 1),
            gear: (1, 1),
            feed: (counts_per_rev, 1),
            velocity_factor: (1, 1),
            acceleration_factor: (1, 1),
            polarity: 0,
            scaling: None,
        }
    }
}

/// Rounds half away from zero, bit for bit `libm::round` (and `f64::round`):
/// below 2^52 in magnitude by truncating to an integer (exact there), which
/// is a few instructions where a target without SSE4.1 calls a library
/// routine; the drive and the personalities round their live values every
/// control period.
#[inline]
pub fn round(x: f64) -> f64 {
    const EXACT: f64 = 4_503_599_627_370_496.0; // 2^52
    if x.is_nan() || x.abs() >= EXACT {
        return libm::round(x);
    }
    let t = x as i64;
    let f = x - t as f64;
    let r = if f >= 0.5 {
        t + 1
    } else if f <= -0.5 {
        t - 1
    } else {
        t
    };
    // A zero keeps the sign of `x` (-0.3 rounds to -0.0); any other result
    // has it already.
    f64::from_bits((r as f64).to_bits() | (x.to_bits() & (1 << 63)))
}

/// Resolved conversions between user units, increments and motor radians.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Units {
    /// Increments per position unit.
    pos: Ratio,
    /// Position units/s per velocity unit.
    vel: Ratio,
    /// Position units/s² per acceleration unit.
    acc: Ratio,
    pos_sign: f64,
    vel_sign: f64,
    pos_sign_i: i64,
    inc_per_rad: f64,
    pos_per_inc: f64,
    inc_per_pos: f64,
    /// `vel` and `acc` as floats: converting the exact ratios costs two
    /// 128-bit conversions a call, and the control step converts often.
    vel_f: f64,
    acc_f: f64,
    /// `pos` as 64-bit integers, `(0, 0)` if either does not fit: the
    /// fast path of [`Units::inc_frac_to_pos`].
    pos_i64: (i64, i64),
    /// `pos.den` as a float.
    den_f: f64,
}

impl Default for Units {
    /// One position unit = one increment, 2^20 increments per revolution.
    fn default() -> Self {
        Units::new(&FactorGroup::increments(1 << 20)).expect("valid default")
    }
}

fn ratio(r: (u32, u32)) -> Option<Ratio> {
    Ratio::new(u128::from(r.0), u128::from(r.1))
}

impl Units {
    /// Resolves a factor group; `None` if any numerator or denominator is 0.
    pub fn new(f: &FactorGroup) -> Option<Units> {
        let enc = ratio(f.encoder)?;
        let (pos, vel, acc) = match &f.scaling {
            Some(s) => s.ratios()?,
            None => (
                enc.times(ratio(f.gear)?)?.times(ratio(f.feed)?.inv())?,
                ratio(f.velocity_factor)?,
                ratio(f.acceleration_factor)?,
            ),
        };
        let inc_per_rad = enc.to_f64() / (2.0 * PI);
        let pos_sign_i = if f.polarity & 0x80 != 0 { -1 } else { 1 };
        Some(Units {
            pos,
            vel,
            acc,
            pos_sign: pos_sign_i as f64,
            vel_sign: if f.polarity & 0x40 != 0 { -1.0 } else { 1.0 },
            pos_sign_i,
            inc_per_rad,
            pos_per_inc: pos.inv().to_f64(),
            inc_per_pos: pos.to_f64(),
            vel_f: vel.to_f64(),
            acc_f: acc.to_f64(),
            den_f: pos.den as f64,
            pos_i64: match (i64::try_from(pos.num), i64::try_from(pos.den)) {
                (Ok(n), Ok(d)) => (n, d),
                _ => (0, 0),
            },
        })
    }

    /// Increments per position unit, exact.
    pub fn position_ratio(&self) -> Ratio {
        self.pos
    }

    /// Position \[units\] → increments, exact (rounded to the nearest increment).
    pub fn pos_to_inc(&self, p: i64) -> i64 {
        self.pos.apply_round(p.saturating_mul(self.pos_sign_i))
    }

    /// Increments → position \[units\], exact (rounded to the nearest unit).
    pub fn inc_to_pos(&self, inc: i64) -> i64 {
        self.pos.inv().apply_round(inc).saturating_mul(self.pos_sign_i)
    }

    /// Position \[units\] → increments, exact and unrounded: a whole part
    /// and `frac / den` of an increment (`den` = [`Units::position_ratio`]
    /// denominator, `0 <= frac < den`). Where a position unit is finer than
    /// an increment, a reference taken at `p` (homing) keeps the part of an
    /// increment [`Units::pos_to_inc`] would round away.
    pub fn pos_to_inc_exact(&self, p: i64) -> (i64, i128) {
        let (num, den) = (self.pos.num as i128, self.pos.den as i128);
        let x = i128::from(p.saturating_mul(self.pos_sign_i)).saturating_mul(num);
        (x.div_euclid(den).clamp(i128::from(i64::MIN), i128::from(i64::MAX)) as i64, x.rem_euclid(den))
    }

    /// Increments plus `frac / den` of an increment (see
    /// [`Units::pos_to_inc_exact`]) → position \[units\], exact (rounded to
    /// the nearest unit).
    pub fn inc_frac_to_pos(&self, inc: i64, frac: i128) -> i64 {
        // In 64 bits when everything fits (the usual case): the drive
        // converts its position several times a control period.
        let (num, den) = self.pos_i64;
        if let Ok(fr) = i64::try_from(frac)
            && let Some(p) = inc.checked_mul(den).and_then(|x| x.checked_add(fr))
            && num > 0
            && p > i64::MIN + num
            && p < i64::MAX - num
        {
            let q = if p >= 0 { (p + num / 2) / num } else { -((-p + num / 2) / num) };
            return q.saturating_mul(self.pos_sign_i);
        }
        self.inc_frac_to_pos_wide(inc, frac)
    }

    /// [`Units::inc_frac_to_pos`] in 128 bits.
    fn inc_frac_to_pos_wide(&self, inc: i64, frac: i128) -> i64 {
        let (num, den) = (self.pos.num as i128, self.pos.den as i128);
        let p = i128::from(inc).saturating_mul(den).saturating_add(frac);
        let q = div_round(p, num);
        (q.clamp(i128::from(i64::MIN), i128::from(i64::MAX)) as i64).saturating_mul(self.pos_sign_i)
    }

    /// `frac / den` of an increment (see [`Units::pos_to_inc_exact`]) as a float.
    pub fn frac_to_inc_f(&self, frac: i128) -> f64 {
        // The usual reference has no fraction: no 128-bit conversions then
        // (the control step asks every period).
        if frac == 0 {
            return 0.0;
        }
        // Through 64 bits when it fits (the same correctly rounded value):
        // a 128-bit conversion is a library call.
        let f = i64::try_from(frac).map_or_else(|_| frac as f64, |v| v as f64);
        f / self.den_f
    }

    /// Position \[units\] → increments as a float (set-points, derivatives).
    pub fn pos_to_inc_f(&self, p: f64) -> f64 {
        p * self.inc_per_pos * self.pos_sign
    }

    /// Increments → position units as a float.
    pub fn inc_to_pos_f(&self, inc: f64) -> f64 {
        inc * self.pos_per_inc * self.pos_sign
    }

    /// Velocity units → position units/s (magnitude, no polarity).
    pub fn vel_to_pos(&self, v: f64) -> f64 {
        v * self.vel_f
    }

    /// Position units/s → velocity units (magnitude, no polarity).
    pub fn pos_to_vel(&self, v: f64) -> f64 {
        v / self.vel_f
    }

    /// Acceleration units → position units/s² (magnitude).
    pub fn acc_to_pos(&self, a: f64) -> f64 {
        a * self.acc_f
    }

    /// A signed velocity-mode value \[velocity units\] → increments/s,
    /// applying the velocity polarity (607Eh bit 6).
    pub fn vel_units_to_inc_s(&self, v: f64) -> f64 {
        v * self.vel_f * self.inc_per_pos * self.vel_sign
    }

    /// Increments/s → velocity units, with the velocity polarity.
    pub fn inc_s_to_vel_units(&self, w: f64) -> f64 {
        w * self.pos_per_inc / self.vel_f * self.vel_sign
    }

    /// A velocity-unit value (60FFh, 606Ch) → position units/s in the
    /// position frame (velocity factor 6096h, polarities 607Eh bits 6 and 7).
    pub fn velocity_to_frame(&self, v: f64) -> f64 {
        v * self.vel_f * self.vel_sign * self.pos_sign
    }

    /// Position units/s (position frame) → velocity units (606Bh, 606Ch).
    pub fn frame_to_velocity(&self, v: f64) -> f64 {
        v / self.vel_f * self.vel_sign * self.pos_sign
    }

    /// Increments → motor angle \[rad\].
    pub fn inc_to_rad(&self, inc: f64) -> f64 {
        inc / self.inc_per_rad
    }

    /// Motor angle \[rad\] → increments.
    pub fn rad_to_inc(&self, rad: f64) -> f64 {
        rad * self.inc_per_rad
    }

    /// Position units → motor angle \[rad\].
    pub fn pos_to_rad(&self, p: f64) -> f64 {
        self.inc_to_rad(self.pos_to_inc_f(p))
    }

    /// Motor angle \[rad\] → position units.
    pub fn rad_to_pos(&self, rad: f64) -> f64 {
        self.inc_to_pos_f(self.rad_to_inc(rad))
    }
}

/// Converts a stream of relative moves to increments, carrying the
/// remainder so the sum of the converted moves is always the exact
/// conversion of the sum (no drift over any number of moves).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Carry {
    rem: i128,
}

impl Carry {
    /// Increments for a relative move of `d` position units under `r`
    /// (increments per unit): `floor((Σd · num + r₀) / den)` so far.
    pub fn delta_to_inc(&mut self, r: Ratio, d: i64) -> i64 {
        let den = r.den as i128;
        let total = i128::from(d).saturating_mul(r.num as i128).saturating_add(self.rem);
        let q = total.div_euclid(den);
        self.rem = total.rem_euclid(den);
        q.clamp(i128::from(i64::MIN), i128::from(i64::MAX)) as i64
    }

    /// The remainder carried (in 1/den increments).
    pub fn remainder(&self) -> i128 {
        self.rem
    }
}

/// `p / num` rounded half away from zero (`num` > 0). In 64 bits when the
/// operands fit (the usual case): a 128-bit division is a library call, and
/// the drive asks for its position every control period.
#[inline]
fn div_round(p: i128, num: i128) -> i128 {
    if let (Ok(p), Ok(n)) = (i64::try_from(p), i64::try_from(num))
        && n > 0
        && p > i64::MIN + n
        && p < i64::MAX - n
    {
        return i128::from(if p >= 0 { (p + n / 2) / n } else { -((-p + n / 2) / n) });
    }
    div_round_wide(p, num)
}

fn div_round_wide(p: i128, num: i128) -> i128 {
    if p >= 0 { (p + num / 2) / num } else { -((-p + num / 2) / num) }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::strategy::Strategy;

    #[test]
    fn round_edges_are_libm_round() {
        let edges = [
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.5,
            -1.5,
            2.5,
            0.49999999999999994,
            -0.49999999999999994,
            0.3,
            -0.3,
            4_503_599_627_370_495.5,
            -4_503_599_627_370_495.5,
            4_503_599_627_370_496.0,
            9.3e18,
            -9.3e18,
            f64::MAX,
            f64::MIN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::MIN_POSITIVE,
            -f64::MIN_POSITIVE,
        ];
        for x in edges {
            assert_eq!(round(x).to_bits(), libm::round(x).to_bits(), "{x}");
        }
        assert!(round(f64::NAN).is_nan());
    }

    #[test]
    fn milli_degree_ratio() {
        let f = FactorGroup { feed: (360_000, 1), ..FactorGroup::increments(1 << 20) };
        let u = Units::new(&f).unwrap();
        // 2^20 / 360000 reduced by 64 → 16384 / 5625.
        assert_eq!(u.position_ratio(), Ratio { num: 16384, den: 5625 });
        assert_eq!(u.pos_to_inc(5625), 16384);
        assert_eq!(u.inc_to_pos(16384), 5625);
        assert_eq!(u.pos_to_inc(-1), -3); // -2.9127 → -3
    }

    #[test]
    fn polarity_negates_positions() {
        let f = FactorGroup { polarity: 0xC0, ..FactorGroup::increments(1000) };
        let u = Units::new(&f).unwrap();
        assert_eq!(u.pos_to_inc(10), -10);
        assert_eq!(u.inc_to_pos(-10), 10);
        assert_eq!(u.vel_units_to_inc_s(5.0), -5.0);
    }

    #[test]
    fn scaling_replaces_the_chain() {
        // Technosoft iPOS §5.1.10.1: 6093h = 20000h / 10000h is 2:1;
        // internal velocity 1/65536 increment per ms, acceleration per ms².
        let s = Scaling { position: (0x2_0000, 0x1_0000), ..Scaling::unit((125, 8192), (15_625, 1024)) };
        let f = FactorGroup { scaling: Some(s), feed: (7, 3), ..FactorGroup::increments(2000) };
        let u = Units::new(&f).unwrap();
        assert_eq!(u.pos_to_inc(1000), 2000);
        assert_eq!(u.inc_to_pos(2000), 1000);
        // 65536 internal = 1 increment/ms = 1000 increments/s = 500 units/s.
        assert_eq!(u.vel_to_pos(65536.0), 500.0);
        assert_eq!(u.acc_to_pos(65536.0), 500_000.0);
        let s = Scaling { velocity: (131_072, 60), ..s };
        let u = Units::new(&FactorGroup { scaling: Some(s), ..f }).unwrap();
        // 6094h in rpm: 1 rpm = 2000/60 increments/s = 1000/60 units/s.
        assert!((u.vel_to_pos(600.0) - 10_000.0).abs() < 1e-9);
        let zero = Scaling { acceleration: (0, 1), ..s };
        assert!(Units::new(&FactorGroup { scaling: Some(zero), ..f }).is_none());
    }

    #[test]
    fn zero_factor_refused() {
        let f = FactorGroup { gear: (0, 1), ..FactorGroup::increments(1000) };
        assert!(Units::new(&f).is_none());
    }

    proptest::proptest! {
        #[test]
        fn div_round_matches_the_128_bit_division(
            p in proptest::prop_oneof![
                // The wide formula's own range (`p ± num / 2` fits).
                (-(i128::MAX / 2)..i128::MAX / 2),
                proptest::num::i64::ANY.prop_map(i128::from),
                (-1_000_000i128..1_000_000),
            ],
            num in proptest::prop_oneof![
                1i128..=1_000_000,
                1i128..=i128::from(i64::MAX),
                (i128::from(i64::MAX) - 3)..=(i128::from(i64::MAX) + 3),
                1i128..=i128::MAX / 2,
            ],
        ) {
            proptest::prop_assert_eq!(div_round(p, num), div_round_wide(p, num));
        }

        /// `round` is `libm::round` bit for bit.
        #[test]
        fn round_is_libm_round(
            x in proptest::prop_oneof![
                proptest::num::f64::ANY,
                -1e6f64..1e6,
                (-2_000_000i64..2_000_000).prop_map(|k| k as f64 / 2.0),
                (-2_000_000i64..2_000_000).prop_map(|k| k as f64 / 2.0 + 1e-9),
            ],
        ) {
            proptest::prop_assert_eq!(round(x).to_bits(), libm::round(x).to_bits(), "{}", x);
        }

        /// `frac_to_inc_f` converts through 64 bits to the same float.
        #[test]
        fn frac_to_inc_f_is_the_128_bit_quotient(
            frac in proptest::prop_oneof![proptest::num::i128::ANY, proptest::num::i64::ANY.prop_map(i128::from)],
            enc in 1u32..=u32::MAX, feed in 1u32..=u32::MAX,
        ) {
            let f = FactorGroup { feed: (feed, 1), ..FactorGroup::increments(enc) };
            let u = Units::new(&f).unwrap();
            let expect = if frac == 0 { 0.0 } else { frac as f64 / u.position_ratio().den as f64 };
            proptest::prop_assert_eq!(u.frac_to_inc_f(frac).to_bits(), expect.to_bits());
        }

        /// The 64-bit path of `inc_frac_to_pos` gives the 128-bit result.
        #[test]
        fn inc_frac_to_pos_matches_the_128_bit_formula(
            inc in proptest::prop_oneof![proptest::num::i64::ANY, -1i64 << 40..1i64 << 40],
            enc in 1u32..=u32::MAX, feed in 1u32..=u32::MAX, gear in 1u32..=u32::MAX, pol in 0u8..2,
            frac_seed in proptest::num::u64::ANY,
        ) {
            let f = FactorGroup { feed: (feed, 1), gear: (gear, 3), polarity: pol << 7, ..FactorGroup::increments(enc) };
            let u = Units::new(&f).unwrap();
            let frac = i128::from(frac_seed) % u.position_ratio().den as i128;
            proptest::prop_assert_eq!(u.inc_frac_to_pos(inc, frac), u.inc_frac_to_pos_wide(inc, frac));
        }

        /// A reference taken at `p` reads back `p` exactly, from any
        /// encoder position, whichever of unit and increment is finer.
        #[test]
        fn exact_reference_reads_back(p in -2_000_000_000i64..2_000_000_000, counts in -1i64 << 40..1i64 << 40,
                                      enc in 1u32..1 << 24, feed in 1u32..1_000_000, pol in 0u8..2) {
            let f = FactorGroup { feed: (feed, 1), polarity: pol << 7, ..FactorGroup::increments(enc) };
            let u = Units::new(&f).unwrap();
            let (whole, frac) = u.pos_to_inc_exact(p);
            proptest::prop_assert!((0..u.position_ratio().den as i128).contains(&frac));
            // A shift by `whole - counts` from `counts` lands on `whole`.
            let offset = whole - counts;
            proptest::prop_assert_eq!(u.inc_frac_to_pos(counts + offset, frac), p);
            // Without a fraction it is the plain conversion.
            proptest::prop_assert_eq!(u.inc_frac_to_pos(whole, 0), u.inc_to_pos(whole));
        }

        #[test]
        fn carry_never_drifts(moves in proptest::collection::vec(-1_000_000i64..1_000_000, 1..200),
                              num in 1u32..100_000, den in 1u32..100_000) {
            let r = Ratio::new(u128::from(num), u128::from(den)).unwrap();
            let mut c = Carry::default();
            let mut sum_inc: i128 = 0;
            let mut sum_units: i128 = 0;
            for d in &moves {
                sum_inc += i128::from(c.delta_to_inc(r, *d));
                sum_units += i128::from(*d);
            }
            // Analytic: floor(Σd · num / den).
            let exact = (sum_units * i128::from(num)).div_euclid(i128::from(den));
            proptest::prop_assert_eq!(sum_inc, exact);
        }
    }
}
