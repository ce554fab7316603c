//! What EtherCAT needs of a CoE dictionary and its description
//! (ETG.1000.6 sync manager and PDO objects, the masters' mailbox needs,
//! and the limits a device's manual sets).

use crate::check::{CheckOptions, Disagreement, Report, Source, access_text};
use crate::description::{SlaveDescription, SmKind};
use crate::pdo::{RX_MAPPING, TX_MAPPING, default_assignment, mapping_values};
use drivebus_coe::access_bits;
use drivebus_coe::mailbox::{MAX_MAILBOX_SIZE, MIN_MAILBOX_SIZE};
use drivebus_od::ObjectDictionary;

/// Sub-indices `1..=n` the object lacks, as `2–4`-style ranges.
fn missing(d: &SlaveDescription, index: u16, n: u8) -> Option<String> {
    let o = d.object(index)?;
    let gaps: Vec<u8> = (1..=n).filter(|s| o.get(*s).is_none()).collect();
    let mut parts = Vec::new();
    let mut i = 0;
    while i < gaps.len() {
        let mut j = i;
        while j + 1 < gaps.len() && gaps[j + 1] == gaps[j] + 1 {
            j += 1;
        }
        parts.push(if i == j { format!("{}", gaps[i]) } else { format!("{}–{}", gaps[i], gaps[j]) });
        i = j + 1;
    }
    (!parts.is_empty()).then(|| parts.join(", "))
}

fn writable(d: &SlaveDescription, index: u16, sub: u8) -> Option<u16> {
    d.object(index)?.get(sub).map(|s| s.access)
}

/// What an EtherCAT master and the device's manual need of `od`, as `d`
/// describes it (`d` built from `od`):
///
/// * 1C00h gives each sync manager's type (ETG.1000.6: 1 mailbox out,
///   2 mailbox in, 3 outputs, 4 inputs), matching the `Sm` elements;
/// * 1C12h/1C13h exist for the process data SMs, with one entry per
///   mapping object (or `opts.assign_entries`), their default entries
///   name existing mapping objects, and, with `PdoAssign`, sub 0 is
///   writable;
/// * every mapping object offers `opts.mapping_entries` entries, is
///   writable with `PdoConfig`, maps existing objects that are mappable in
///   its direction with their own bit size, and stays within
///   `opts.max_pdo_bits`;
/// * 1018h has subs 1–4 (masters read the identity over CoE);
/// * the mailboxes are within 32..=1486 bytes and SM1 is large enough for
///   ethercrab with this many objects.
pub fn check_ethercat(d: &SlaveDescription, od: &ObjectDictionary, opts: &CheckOptions) -> Vec<Disagreement> {
    let mut r = Report::new(Source::EtherCat);
    sync_manager_types(&mut r, d);
    let coe = d.mailbox.and_then(|m| m.coe);
    for (rx, assign, range, kind) in
        [(true, 0x1C12u16, RX_MAPPING, SmKind::Outputs), (false, 0x1C13, TX_MAPPING, SmKind::Inputs)]
    {
        let maps: Vec<u16> = od.objects().iter().map(|o| o.index).filter(|i| range.contains(i)).collect();
        if d.sm(kind).is_some() {
            assignment(&mut r, d, od, assign, &maps, coe.is_some_and(|c| c.pdo_assign), opts, rx);
        }
        for &m in &maps {
            mapping(&mut r, d, od, m, rx, coe.is_some_and(|c| c.pdo_config), opts);
        }
    }
    match d.object(0x1018) {
        None => r.add(Some(0x1018), None, "exists", "absent", "identity object", "ETG.1000.6"),
        Some(_) => {
            if let Some(m) = missing(d, 0x1018, 4) {
                r.add(Some(0x1018), None, "sub-indices", format!("{m} missing"), "1–4", "ETG.1000.6");
            }
        }
    }
    mailbox_sizes(&mut r, d);
    r.out
}

fn sync_manager_types(r: &mut Report, d: &SlaveDescription) {
    if d.sync_managers.is_empty() {
        return;
    }
    let Some(o) = d.object(0x1C00) else {
        r.add(Some(0x1C00), None, "exists", "absent", "sync manager communication types", "ETG.1000.6");
        return;
    };
    let n = d.sync_managers.len();
    let count = o.get(0).map(|s| drivebus_od::le_u64(&s.default));
    if count != Some(n as u64) {
        let got = count.map_or_else(|| "absent".to_string(), |c| c.to_string());
        r.add(Some(0x1C00), Some(0), "default", got, n.to_string(), "one entry per Sm element");
    }
    for (i, sm) in d.sync_managers.iter().enumerate() {
        let sub = i as u8 + 1;
        let got = o.get(sub).map(|s| drivebus_od::le_u64(&s.default));
        let want = u64::from(sm.kind.code());
        if got != Some(want) {
            let got = got.map_or_else(|| "absent".to_string(), |v| v.to_string());
            let note = format!("SM{i} is {}", sm.kind.name());
            r.add(Some(0x1C00), Some(sub), "default", got, want.to_string(), &note);
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn assignment(
    r: &mut Report,
    d: &SlaveDescription,
    od: &ObjectDictionary,
    assign: u16,
    maps: &[u16],
    pdo_assign: bool,
    opts: &CheckOptions,
    rx: bool,
) {
    let what = if rx { "RxPDO assignment (SM2)" } else { "TxPDO assignment (SM3)" };
    if d.object(assign).is_none() {
        r.add(Some(assign), None, "exists", "absent", what, "ETG.1000.6");
        return;
    }
    let n = opts.assign_entries.unwrap_or(maps.len().min(255) as u8);
    if let Some(m) = missing(d, assign, n) {
        let note = format!("one entry per mapping object: {} of them", maps.len());
        r.add(Some(assign), None, "sub-indices", format!("{m} missing"), format!("1–{n}"), &note);
    }
    if pdo_assign && opts.writable_counts {
        for (sub, s) in d.object(assign).map_or(&[][..], |o| &o.subs[..]).iter().map(|s| (s.sub, s)) {
            if s.access & access_bits::WRITE_PREOP == 0 {
                let note = if sub == 0 {
                    "PdoAssign: the master writes 0, the entries, then the count"
                } else {
                    "PdoAssign"
                };
                r.add(Some(assign), Some(sub), "access", access_text(s.access), "writable in PRE-OP", note);
            }
        }
    }
    for p in default_assignment(od, rx).unwrap_or_default() {
        if !maps.contains(&p) {
            r.add(Some(assign), None, "default entry", format!("{p:04X}h"), "an existing mapping object", "");
        }
    }
}

fn mapping(
    r: &mut Report,
    d: &SlaveDescription,
    od: &ObjectDictionary,
    m: u16,
    rx: bool,
    pdo_config: bool,
    opts: &CheckOptions,
) {
    if let Some(n) = opts.mapping_entries
        && let Some(gaps) = missing(d, m, n)
    {
        r.add(
            Some(m),
            None,
            "sub-indices",
            format!("{gaps} missing"),
            format!("1–{n}"),
            "mapping entries the device offers",
        );
    }
    if pdo_config
        && opts.writable_counts
        && writable(d, m, 0).is_some_and(|w| w & access_bits::WRITE_PREOP == 0)
    {
        let w = writable(d, m, 0).unwrap_or(0);
        r.add(Some(m), Some(0), "access", access_text(w), "writable in PRE-OP", "PdoConfig");
    }
    let dir = if rx { access_bits::RXPDO } else { access_bits::TXPDO };
    let mut bits = 0u32;
    for (k, v) in mapping_values(od, m).into_iter().enumerate() {
        let (index, sub, len) = ((v >> 16) as u16, (v >> 8) as u8, v & 0xFF);
        bits += len;
        if (0x0001..=0x0007).contains(&index) && sub == 0 {
            continue; // a dummy entry
        }
        let at = Some(k as u8 + 1);
        let target = d.object(index).and_then(|o| o.get(sub));
        match target {
            None => r.add(
                Some(m),
                at,
                "default entry",
                format!("{index:04X}:{sub:02X}"),
                "an existing object",
                "",
            ),
            Some(t) => {
                if t.access & dir == 0 {
                    let want = if rx { "RxPDO-mappable" } else { "TxPDO-mappable" };
                    r.add(
                        Some(m),
                        at,
                        "default entry",
                        format!("{index:04X}:{sub:02X} not mappable"),
                        want,
                        "",
                    );
                }
                if t.bits() != len {
                    let got = format!("{index:04X}:{sub:02X} {len} bits");
                    r.add(Some(m), at, "default entry", got, format!("{} bits", t.bits()), "");
                }
            }
        }
    }
    if let Some(max) = opts.max_pdo_bits
        && bits > max
    {
        r.add(Some(m), None, "default mapping", format!("{bits} bits"), format!("at most {max}"), "");
    }
}

fn mailbox_sizes(r: &mut Report, d: &SlaveDescription) {
    for kind in [SmKind::MBoxOut, SmKind::MBoxIn] {
        let Some((n, sm)) = d.sm(kind) else { continue };
        let size = usize::from(sm.default_size.unwrap_or(0));
        if !(MIN_MAILBOX_SIZE..=MAX_MAILBOX_SIZE).contains(&size) {
            let want = format!("{MIN_MAILBOX_SIZE}..={MAX_MAILBOX_SIZE}");
            r.add(None, None, &format!("SM{n} size"), size.to_string(), want, "mailbox sizes masters accept");
        }
        if kind == SmKind::MBoxIn && d.mailbox.is_some_and(|m| m.coe.is_some()) {
            let need = d.ethercrab_min_mailbox_in();
            if size < need {
                let note = format!("ethercrab 0.7.1 OD list and uploads with {} objects", d.object_count());
                r.add(
                    None,
                    None,
                    &format!("SM{n} size"),
                    size.to_string(),
                    format!("at least {need}"),
                    &note,
                );
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::description::DeviceFacts;
    use drivebus_od::{Access, DataType, Object, ObjectCode, SubObject, Value};

    fn od(sm3_type: u8, map: &[u32]) -> ObjectDictionary {
        let mut od = ObjectDictionary::new();
        let mut c = Object::array(0x1C00, "SM types", DataType::Unsigned8, Access::Ro, 4, Value::U8(1));
        for (i, t) in [1u8, 2, 3, sm3_type].into_iter().enumerate() {
            c.subs_mut()[i + 1].default = vec![t];
        }
        od.insert(c);
        od.insert(
            Object::record(0x1018, "Identity")
                .with_sub(SubObject::new(1, "v", DataType::Unsigned32, Access::Ro, Value::U32(1)))
                .with_sub(SubObject::new(2, "p", DataType::Unsigned32, Access::Ro, Value::U32(1)))
                .with_sub(SubObject::new(3, "r", DataType::Unsigned32, Access::Ro, Value::U32(1)))
                .with_sub(SubObject::new(4, "s", DataType::Unsigned32, Access::Ro, Value::U32(1))),
        );
        od.insert(Object::var(0x6041, "Statusword", DataType::Unsigned16, Access::Ro, Value::U16(0)));
        let mut cw = Object::var(0x6040, "Controlword", DataType::Unsigned16, Access::Rww, Value::U16(0));
        cw.subs_mut()[0].pdo_mappable = true;
        od.insert(cw);
        for (assign, first) in [(0x1C12u16, 0x1600u16), (0x1C13, 0x1A00)] {
            let mut a =
                Object::array(assign, "assign", DataType::Unsigned16, Access::Rw, 1, Value::U16(first));
            a.subs_mut()[0].access = Access::Rw;
            od.insert(a);
        }
        for index in [0x1600u16, 0x1A00] {
            let mut o = Object::with_code(index, ObjectCode::Record, "map").with_sub(SubObject::new(
                0,
                "n",
                DataType::Unsigned8,
                Access::Rw,
                Value::U8(map.len() as u8),
            ));
            for (k, v) in map.iter().enumerate() {
                o = o.with_sub(SubObject::new(
                    k as u8 + 1,
                    "e",
                    DataType::Unsigned32,
                    Access::Rw,
                    Value::U32(*v),
                ));
            }
            od.insert(o);
        }
        od
    }

    fn found(od: &ObjectDictionary, opts: &CheckOptions) -> Vec<String> {
        let d = SlaveDescription::new(od, &DeviceFacts::new(1, "v", 1, 1, "p"));
        check_ethercat(&d, od, opts).iter().map(ToString::to_string).collect()
    }

    #[test]
    fn a_complete_dictionary_passes() {
        let od = od(4, &[0x6040_0010]);
        // 1A00h maps the controlword too, which is not TxPDO-mappable.
        assert_eq!(
            found(&od, &CheckOptions::default()),
            ["1A00h:01 default entry: dictionary 6040:00 not mappable; EtherCAT needs TxPDO-mappable"]
        );
    }

    #[test]
    fn each_need_reports() {
        let od = od(3, &[0x6040_0020, 0x7000_0008, 0x0005_0008]);
        let opts =
            CheckOptions { mapping_entries: Some(4), max_pdo_bits: Some(40), ..CheckOptions::default() };
        let got = found(&od, &opts);
        for want in [
            "1C00h:04 default: dictionary 3; EtherCAT needs 4 (SM3 is Inputs)",
            "1600h sub-indices: dictionary 4 missing; EtherCAT needs 1–4",
            "1600h:01 default entry: dictionary 6040:00 32 bits; EtherCAT needs 16 bits",
            "1600h:02 default entry: dictionary 7000:00; EtherCAT needs an existing object",
            "1600h default mapping: dictionary 48 bits; EtherCAT needs at most 40",
        ] {
            assert!(got.iter().any(|g| g.starts_with(want)), "{want:?} not in {got:#?}");
        }
        assert!(!got.iter().any(|g| g.contains("0005")), "dummy entries are fine: {got:#?}");
    }

    #[test]
    fn mailbox_sizes_and_ranges() {
        let od = od(4, &[0x6041_0010]);
        let mut f = DeviceFacts::new(1, "v", 1, 1, "p");
        f.mailbox_area = Some(crate::description::MailboxArea {
            rx_offset: 0x1000,
            rx_size: 16,
            tx_offset: 0x1100,
            tx_size: 20,
        });
        let d = SlaveDescription::new(&od, &f);
        let got: Vec<String> =
            check_ethercat(&d, &od, &CheckOptions::default()).iter().map(ToString::to_string).collect();
        assert!(
            got.iter().any(|g| g.starts_with("SM0 size: dictionary 16; EtherCAT needs 32..=1486")),
            "{got:#?}"
        );
        assert!(
            got.iter().any(|g| g.starts_with("SM1 size: dictionary 20; EtherCAT needs at least 30")),
            "{got:#?}"
        );
        assert_eq!(missing(&d, 0x1018, 6).as_deref(), Some("5–6"));
        assert_eq!(missing(&d, 0x1018, 4), None);
    }
}
