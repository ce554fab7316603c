//! `scan`, `nmt`, `pdo`, `lss` and `slcan-pty`.

use std::collections::BTreeMap;
use std::time::Duration;

use anyhow::{Context, anyhow, bail};
use drivebus_can::Frame;
use drivebus_lss::codec::LssResponse;
use drivebus_lss::{FastScan, FastScanOutcome, LssAddress, LssMode, master as lssm};
use drivebus_od::SdoAbort;

use crate::args::{Global, LssCmd, NmtArgs, NmtKind, PdoCmd, PdoDir, PdoMapArgs, ScanArgs, SlcanPtyArgs};
use crate::eds_cmd::{load_global_eds, object_name};
use crate::link::{Link, SdoFailure, need_node, parse_index, parse_num, parse_sub};
use crate::output::outln;
use crate::vdrive::{DriveSpec, spawn_on_hub};

/// `drivebus scan`: SDO 1000h sweep, then identity of each node found.
pub async fn scan(g: &Global, a: &ScanArgs) -> anyhow::Result<()> {
    if a.from > a.to {
        bail!("--from {} is above --to {}", a.from, a.to);
    }
    let mut link = Link::open(g).await?;
    for n in a.from..=a.to {
        link.send(Frame::new(0x600 + u16::from(n), &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0])).await?;
    }
    let deadline = tokio::time::Instant::now() + Duration::from_millis(a.wait.max(1));
    let mut found: BTreeMap<u8, Option<u32>> = BTreeMap::new();
    while let Some(f) = link.recv_until(deadline).await? {
        let Some(id) = f.std_id() else { continue };
        let d = f.raw_data();
        match id {
            0x581..=0x5FF if d[1..3] == [0x00, 0x10] => {
                let n = (id - 0x580) as u8;
                if (a.from..=a.to).contains(&n) {
                    let dt = (d[0] & 0xE3 == 0x43).then(|| u32::from_le_bytes([d[4], d[5], d[6], d[7]]));
                    found.insert(n, dt);
                }
            }
            _ => {}
        }
    }
    let mut rows = Vec::new();
    for (&n, &dt) in &found {
        let name = link
            .upload(n, 0x1008, 0)
            .await
            .ok()
            .map(|b| String::from_utf8_lossy(&b).trim_end_matches('\0').to_owned());
        let vendor = link.read_u64(n, 0x1018, 1).await.ok();
        let product = link.read_u64(n, 0x1018, 2).await.ok();
        rows.push((n, dt, name, vendor, product));
    }
    if g.json {
        let items: Vec<_> = rows
            .iter()
            .map(|(n, dt, name, v, p)| serde_json::json!({"node": n, "device_type": dt, "name": name, "vendor_id": v, "product_code": p}))
            .collect();
        outln!("{}", serde_json::json!({"bus": g.bus, "nodes": items}));
        return Ok(());
    }
    if rows.is_empty() {
        outln!("no node answered on {} (node-IDs {}..{})", g.bus, a.from, a.to);
        return Ok(());
    }
    outln!("{:<5} {:<12} {:<12} {:<12} name", "node", "device type", "vendor", "product");
    for (n, dt, name, v, p) in rows {
        let hx = |x: Option<u64>| x.map_or_else(|| "-".to_owned(), |x| format!("0x{x:08X}"));
        outln!(
            "{n:<5} {:<12} {:<12} {:<12} {}",
            hx(dt.map(u64::from)),
            hx(v),
            hx(p),
            name.unwrap_or_else(|| "-".into())
        );
    }
    Ok(())
}

/// `drivebus nmt`.
pub async fn nmt(g: &Global, a: &NmtArgs) -> anyhow::Result<()> {
    let target = if a.all { 0 } else { g.node.ok_or_else(|| anyhow!("give --node N or --all"))? };
    let (cs, what) = match a.command {
        NmtKind::Start => (0x01, "start"),
        NmtKind::Stop => (0x02, "stop"),
        NmtKind::Preop => (0x80, "enter pre-operational"),
        NmtKind::Reset => (0x81, "reset node"),
        NmtKind::ResetComm => (0x82, "reset communication"),
    };
    let mut link = Link::open(g).await?;
    link.nmt(cs, target).await?;
    let who = if target == 0 { "all nodes".to_owned() } else { format!("node {target}") };
    let mut confirmed = None;
    if target != 0 {
        match a.command {
            NmtKind::Reset | NmtKind::ResetComm => {
                let id = 0x700 + u16::from(target);
                let boot = link
                    .wait_for(link.timeout.max(Duration::from_millis(500)), |f| {
                        f.std_id() == Some(id) && f.data() == [0x00]
                    })
                    .await?;
                if boot.is_none() {
                    bail!(
                        "node {target}: no boot-up message within {} ms after NMT {what} (is node {target} on the bus?)",
                        link.timeout.max(Duration::from_millis(500)).as_millis()
                    );
                }
                confirmed = Some("boot-up received");
            }
            NmtKind::Start | NmtKind::Preop => {
                // Both states answer SDO: check the node is there.
                link.upload(target, 0x1000, 0).await?;
                confirmed = Some("node answers SDO");
            }
            NmtKind::Stop => {}
        }
    }
    if g.json {
        outln!("{}", serde_json::json!({"command": what, "node": target, "confirmed": confirmed}));
    } else {
        match confirmed {
            Some(c) => outln!("NMT {what} sent to {who}: {c}"),
            None => outln!("NMT {what} sent to {who}"),
        }
    }
    Ok(())
}

/// One PDO as read from the device.
struct PdoInfo {
    dir: &'static str,
    number: u16,
    cob_id: u32,
    transmission: Option<u8>,
    event_timer: Option<u16>,
    mapping: Vec<u32>,
}

/// `drivebus pdo`.
pub async fn pdo(g: &Global, c: &PdoCmd) -> anyhow::Result<()> {
    let node = need_node(g)?;
    match c {
        PdoCmd::Show => pdo_show(g, node).await,
        PdoCmd::Map(a) => pdo_map(g, node, a).await,
    }
}

fn is_missing(e: &anyhow::Error) -> bool {
    e.downcast_ref::<SdoFailure>()
        .and_then(SdoFailure::abort)
        .is_some_and(|a| a == SdoAbort::NO_OBJECT || a == SdoAbort::NO_SUB_INDEX)
}

async fn pdo_show(g: &Global, node: u8) -> anyhow::Result<()> {
    let eds = load_global_eds(g)?;
    let mut link = Link::open(g).await?;
    let mut pdos = Vec::new();
    for (dir, comm, map) in [("RPDO", 0x1400u16, 0x1600u16), ("TPDO", 0x1800, 0x1A00)] {
        for n in 0..512u16 {
            let cob_id = match link.read_u64(node, comm + n, 1).await {
                Ok(v) => v as u32,
                Err(e) if is_missing(&e) => break,
                Err(e) => return Err(e),
            };
            let transmission = link.read_u64(node, comm + n, 2).await.ok().map(|v| v as u8);
            let event_timer = if dir == "TPDO" {
                link.read_u64(node, comm + n, 5).await.ok().map(|v| v as u16)
            } else {
                None
            };
            let count = link.read_u64(node, map + n, 0).await.unwrap_or(0).min(64) as u8;
            let mut mapping = Vec::new();
            for s in 1..=count {
                mapping.push(link.read_u64(node, map + n, s).await? as u32);
            }
            pdos.push(PdoInfo { dir, number: n + 1, cob_id, transmission, event_timer, mapping });
        }
    }
    let name = |e: u32| {
        let (i, s) = ((e >> 16) as u16, (e >> 8) as u8);
        eds.as_ref().and_then(|x| object_name(x, i, s)).unwrap_or_default()
    };
    if g.json {
        let items: Vec<_> = pdos
            .iter()
            .map(|p| {
                let m: Vec<_> = p
                    .mapping
                    .iter()
                    .map(|&e| serde_json::json!({"index": e >> 16, "sub": (e >> 8) & 0xFF, "bits": e & 0xFF, "name": name(e)}))
                    .collect();
                serde_json::json!({"dir": p.dir, "number": p.number, "cob_id": p.cob_id & 0x1FFF_FFFF, "valid": p.cob_id & 0x8000_0000 == 0,
                    "transmission_type": p.transmission, "event_timer_ms": p.event_timer, "mapping": m})
            })
            .collect();
        outln!("{}", serde_json::json!({"node": node, "pdos": items}));
        return Ok(());
    }
    for p in &pdos {
        let valid = if p.cob_id & 0x8000_0000 == 0 { "valid" } else { "invalid" };
        let tt = p.transmission.map_or_else(|| "-".into(), |t| t.to_string());
        let et = p.event_timer.filter(|&t| t > 0).map(|t| format!(" event timer {t} ms")).unwrap_or_default();
        outln!("{}{} COB-ID 0x{:03X} {valid}, type {tt}{et}", p.dir, p.number, p.cob_id & 0x1FFF_FFFF);
        for &e in &p.mapping {
            outln!("    {:04X}h:{:02X} {:>2} bits  {}", e >> 16, (e >> 8) & 0xFF, e & 0xFF, name(e));
        }
    }
    Ok(())
}

fn parse_entry(s: &str) -> anyhow::Result<u32> {
    let parts: Vec<&str> = s.split(':').collect();
    let [i, sub, bits] = parts[..] else {
        bail!("bad mapping entry `{s}`: expected INDEX:SUB:BITS, e.g. 0x6041:0:16");
    };
    let bits = parse_num(bits)?;
    if bits == 0 || bits > 64 {
        bail!("bad mapping entry `{s}`: BITS must be 1..64");
    }
    Ok((u32::from(parse_index(i)?) << 16) | (u32::from(parse_sub(sub)?) << 8) | bits)
}

async fn pdo_map(g: &Global, node: u8, a: &PdoMapArgs) -> anyhow::Result<()> {
    let entries = a.entries.iter().map(|e| parse_entry(e)).collect::<anyhow::Result<Vec<u32>>>()?;
    let (comm, map) = match a.dir {
        PdoDir::Rpdo => (0x1400 + a.number - 1, 0x1600 + a.number - 1),
        PdoDir::Tpdo => (0x1800 + a.number - 1, 0x1A00 + a.number - 1),
    };
    let mut link = Link::open(g).await?;
    let cob = match &a.cob_id {
        Some(c) => parse_num(c)?,
        None => link.read_u64(node, comm, 1).await? as u32,
    };
    // CiA 301 §7.2.2: invalidate, clear, map, count, validate.
    link.download(node, comm, 1, &(cob | 0x8000_0000).to_le_bytes()).await?;
    link.download(node, map, 0, &[0]).await?;
    for (k, e) in entries.iter().enumerate() {
        link.download(node, map, k as u8 + 1, &e.to_le_bytes()).await?;
    }
    link.download(node, map, 0, &[entries.len() as u8]).await?;
    if let Some(t) = a.transmission {
        link.download(node, comm, 2, &[t]).await?;
    }
    if let Some(t) = a.event_timer {
        link.download(node, comm, 5, &t.to_le_bytes()).await?;
    }
    link.download(node, comm, 1, &(cob & 0x7FFF_FFFF).to_le_bytes()).await?;
    let dir = match a.dir {
        PdoDir::Rpdo => "RPDO",
        PdoDir::Tpdo => "TPDO",
    };
    if g.json {
        outln!(
            "{}",
            serde_json::json!({"node": node, "dir": dir, "number": a.number, "cob_id": cob & 0x7FFF_FFFF, "mapping": entries})
        );
    } else {
        outln!(
            "node {node}: {dir}{} mapped {} entries, COB-ID 0x{:03X} valid",
            a.number,
            entries.len(),
            cob & 0x1FFF_FFFF
        );
    }
    Ok(())
}

/// `drivebus lss`.
pub async fn lss(g: &Global, c: &LssCmd) -> anyhow::Result<()> {
    let mut link = Link::open(g).await?;
    match c {
        LssCmd::Scan => {
            let mut fs =
                FastScan::new(drivebus_can::Duration::from_millis(g.timeout.clamp(10, 1000) / 10 + 10));
            let mut out: Vec<Frame> = Vec::new();
            fs.start(link.now(), &mut out);
            let overall = tokio::time::Instant::now() + Duration::from_secs(30);
            let outcome = loop {
                for f in out.drain(..) {
                    link.send(f).await?;
                }
                if let Some(o) = fs.outcome() {
                    break o;
                }
                if tokio::time::Instant::now() > overall {
                    bail!("LSS fastscan did not finish within 30 s");
                }
                let next = fs.poll(link.now(), &mut out);
                if !out.is_empty() {
                    continue;
                }
                let wait = next.map_or(Duration::from_millis(10), |t| {
                    Duration::from_nanos(t.as_nanos().saturating_sub(link.now().as_nanos()))
                });
                if let Some(f) = link.recv_until(tokio::time::Instant::now() + wait).await? {
                    fs.handle_frame(&f, link.now(), &mut out);
                }
            };
            match outcome {
                FastScanOutcome::Found(addr) => {
                    // Leave the found slave in waiting.
                    link.send(lssm::switch_state_global(LssMode::Waiting)).await?;
                    if g.json {
                        outln!(
                            "{}",
                            serde_json::json!({"found": true, "vendor_id": addr.vendor_id, "product_code": addr.product_code, "revision": addr.revision, "serial": addr.serial})
                        );
                    } else {
                        outln!(
                            "unconfigured LSS slave: vendor 0x{:08X} product 0x{:08X} revision 0x{:08X} serial 0x{:08X}",
                            addr.vendor_id,
                            addr.product_code,
                            addr.revision,
                            addr.serial
                        );
                    }
                }
                FastScanOutcome::NoneFound => {
                    if g.json {
                        outln!("{}", serde_json::json!({"found": false}));
                    } else {
                        outln!("no unconfigured LSS slave answered on {}", g.bus);
                    }
                }
                FastScanOutcome::Lost(field) => {
                    bail!("LSS fastscan lost the slave while scanning {field:?} (frames lost?)")
                }
            }
            Ok(())
        }
        LssCmd::SetNodeId(a) => {
            let wait = link.timeout;
            let parts = [&a.vendor, &a.product, &a.revision, &a.serial];
            if parts.iter().all(|p| p.is_some()) {
                let num = |s: &Option<String>| parse_num(s.as_deref().unwrap_or("0"));
                let addr = LssAddress {
                    vendor_id: num(&a.vendor)?,
                    product_code: num(&a.product)?,
                    revision: num(&a.revision)?,
                    serial: num(&a.serial)?,
                };
                for f in lssm::switch_state_selective(&addr) {
                    link.send(f).await?;
                }
                let ok = link
                    .wait_for(wait, |f| LssResponse::from_frame(f) == Some(LssResponse::SwitchStateSelective))
                    .await?;
                if ok.is_none() {
                    bail!("no LSS slave with that address answered within {} ms", wait.as_millis());
                }
            } else if parts.iter().any(|p| p.is_some()) {
                bail!(
                    "give all of --vendor, --product, --revision and --serial, or none (then the only LSS slave on the bus is configured)"
                );
            } else {
                link.send(lssm::switch_state_global(LssMode::Configuration)).await?;
            }
            link.send(lssm::configure_node_id(a.new_id)).await?;
            let r = link
                .wait_for(wait, |f| {
                    matches!(LssResponse::from_frame(f), Some(LssResponse::ConfigureNodeId { .. }))
                })
                .await?;
            match r.and_then(|f| LssResponse::from_frame(&f)) {
                Some(LssResponse::ConfigureNodeId { error: 0, .. }) => {}
                Some(LssResponse::ConfigureNodeId { error, .. }) => {
                    bail!(
                        "the LSS slave refused node-ID {} (error {error}: {})",
                        a.new_id,
                        if error == 1 { "node-ID out of range" } else { "implementation specific" }
                    )
                }
                _ => bail!(
                    "no LSS slave answered configure node-ID within {} ms (none in configuration state?)",
                    wait.as_millis()
                ),
            }
            if a.store {
                link.send(lssm::store_configuration()).await?;
                let r = link
                    .wait_for(wait, |f| {
                        matches!(LssResponse::from_frame(f), Some(LssResponse::StoreConfiguration { .. }))
                    })
                    .await?;
                if !matches!(
                    r.and_then(|f| LssResponse::from_frame(&f)),
                    Some(LssResponse::StoreConfiguration { error: 0, .. })
                ) {
                    bail!("the LSS slave did not confirm store configuration");
                }
            }
            link.send(lssm::switch_state_global(LssMode::Waiting)).await?;
            if g.json {
                outln!("{}", serde_json::json!({"node_id": a.new_id, "stored": a.store}));
            } else {
                outln!(
                    "LSS: node-ID {} configured{} (active after NMT reset communication)",
                    a.new_id,
                    if a.store { " and stored" } else { "" }
                );
            }
            Ok(())
        }
    }
}

/// `drivebus slcan-pty`.
pub async fn slcan_pty(g: &Global, a: &SlcanPtyArgs) -> anyhow::Result<()> {
    #[cfg(unix)]
    {
        use std::io::Write;
        let specs = DriveSpec::parse_all(&a.drives)?;
        let hub = match drivebus_transport::BusUrl::parse(&g.bus)? {
            drivebus_transport::BusUrl::Virtual { name } => drivebus_transport::hub::virtual_hub(&name),
            _ => bail!("slcan-pty runs on the in-process virtual bus: use --bus virtual (not `{}`)", g.bus),
        };
        crate::fault::install(&hub, &a.faults)?;
        let _drives = spawn_on_hub(&specs, &hub, None, Default::default())?;
        let pty = drivebus_transport::slcan::SlcanPty::spawn(hub.attach())
            .context("cannot open a pseudo-terminal")?;
        {
            let mut out = std::io::stdout().lock();
            writeln!(out, "slcan-pty {}", pty.path().display())?;
            out.flush()?;
        }
        match a.seconds {
            Some(s) => {
                tokio::select! {
                    () = tokio::time::sleep(Duration::from_secs_f64(s.max(0.0))) => {}
                    r = crate::serve::wait_for_signal() => r?,
                }
            }
            None => crate::serve::wait_for_signal().await?,
        }
        for d in _drives {
            d.abort();
        }
        Ok(())
    }
    #[cfg(not(unix))]
    {
        let _ = (g, a);
        bail!("slcan-pty needs a Unix pseudo-terminal")
    }
}
