//! `drivebus-interop-bench URL NODE SECONDS BLOCK_BYTES`
//!
//! With drivebus's master over `URL` (socketcand://HOST:PORT/CHANNEL):
//! expedited uploads of 1000h:0 and downloads of 1017h:0 for SECONDS each,
//! then block download + block upload (CRC) of BLOCK_BYTES into 1F50h:1,
//! checked byte for byte. Prints one JSON object.

use std::time::{Duration, Instant};

use drivebus_master::{Master, Protocol};

#[tokio::main]
async fn main() -> Result<(), Box<dyn std::error::Error>> {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let [url, node, secs, block] = a.as_slice() else {
        return Err("usage: drivebus-interop-bench URL NODE SECONDS BLOCK_BYTES".into());
    };
    let node: u8 = node.parse()?;
    let secs = Duration::from_secs_f64(secs.parse()?);
    let block: usize = block.parse()?;
    let master = Master::new(drivebus_transport::open(url).await?);
    tokio::time::sleep(Duration::from_millis(100)).await; // socketcand rawmode grace
    let sdo = master.sdo(node).timeout(Duration::from_secs(2));

    let device_type: u32 = sdo.read(0x1000, 0).await?;
    let (mut n_up, t0) = (0u64, Instant::now());
    while t0.elapsed() < secs {
        let v: u32 = sdo.read(0x1000, 0).await?;
        if v != device_type {
            return Err(format!("1000h changed: {v:08X} != {device_type:08X}").into());
        }
        n_up += 1;
    }
    let up_rate = n_up as f64 / t0.elapsed().as_secs_f64();

    let (mut n_down, t0) = (0u64, Instant::now());
    while t0.elapsed() < secs {
        sdo.write::<u16>(0x1017, 0, (n_down % 1000) as u16).await?;
        n_down += 1;
    }
    let down_rate = n_down as f64 / t0.elapsed().as_secs_f64();
    sdo.write::<u16>(0x1017, 0, 0).await?;

    let blob: Vec<u8> = (0..block).map(|i| (i % 256) as u8).collect();
    let bsdo = master.sdo(node).timeout(Duration::from_secs(2)).protocol(Protocol::Block).crc(true);
    let t0 = Instant::now();
    bsdo.download(0x1F50, 1, &blob).await?;
    let down_s = t0.elapsed().as_secs_f64();
    let t0 = Instant::now();
    let back = bsdo.upload(0x1F50, 1).await?;
    let up_s = t0.elapsed().as_secs_f64();
    if back != blob {
        return Err(format!(
            "block upload returned {} bytes that differ from the {} downloaded",
            back.len(),
            blob.len()
        )
        .into());
    }
    println!(
        "{{\"expedited_upload_per_s\": {up_rate:.1}, \"expedited_download_per_s\": {down_rate:.1}, \
         \"block_download_kB_per_s\": {:.1}, \"block_upload_kB_per_s\": {:.1}, \"block_bytes\": {block}}}",
        block as f64 / 1000.0 / down_s,
        block as f64 / 1000.0 / up_s
    );
    Ok(())
}
