//! Writes the seed corpus of `fuzz/fuzz_targets/drive_mailbox.rs`: one
//! file per thing a master does through a drive's mailbox (the record
//! format is in `drivebus_ethercat::drive::fuzzing`).
//!
//! ```text
//! cargo run -p drivebus-ethercat --example drive_fuzz_seeds -- fuzz/seeds/drive_mailbox
//! ```

fn mbx(t: u8, c: u8, body: &[u8]) -> Vec<u8> {
    let l = (body.len() as u16).to_le_bytes();
    let mut v = vec![l[0], l[1], 0, 0, 0, t | (c << 4)];
    v.extend_from_slice(body);
    v
}

fn rec(tag: u8, payload: &[u8]) -> Vec<u8> {
    let mut v = vec![tag];
    v.extend_from_slice(&(payload.len() as u16).to_le_bytes());
    v.extend_from_slice(payload);
    v
}

fn upload(c: u8, index: u16, sub: u8) -> Vec<u8> {
    let i = index.to_le_bytes();
    mbx(3, c, &[0x00, 0x20, 0x40, i[0], i[1], sub, 0, 0, 0, 0])
}

fn download(c: u8, index: u16, sub: u8, v: &[u8]) -> Vec<u8> {
    let i = index.to_le_bytes();
    let mut d = [0u8; 4];
    d[..v.len()].copy_from_slice(v);
    mbx(3, c, &[0x00, 0x20, 0x23 | ((4 - v.len() as u8) << 2), i[0], i[1], sub, d[0], d[1], d[2], d[3]])
}

fn seed(profile: u8, steps: &[Vec<u8>]) -> Vec<u8> {
    let mut v = vec![profile];
    for s in steps {
        v.extend_from_slice(s);
    }
    v
}

fn main() -> std::io::Result<()> {
    let dir = std::path::PathBuf::from(
        std::env::args().nth(1).unwrap_or_else(|| "fuzz/seeds/drive_mailbox".into()),
    );
    std::fs::create_dir_all(&dir)?;
    let read = rec(1, &[0]);
    let wait = rec(2, &[5]);
    let mut seeds: Vec<(&str, Vec<u8>)> = vec![
        (
            "upload_identity",
            seed(
                0,
                &[rec(0, &upload(1, 0x1018, 1)), read.clone(), rec(0, &upload(2, 0x1018, 3)), read.clone()],
            ),
        ),
        (
            "e10_remap",
            seed(
                0,
                &[
                    rec(0, &download(1, 0x1C12, 0, &[0])),
                    read.clone(),
                    rec(0, &download(2, 0x1602, 0, &[0])),
                    read.clone(),
                    rec(0, &download(3, 0x1602, 1, &0x6040_0010u32.to_le_bytes())),
                    read.clone(),
                    rec(0, &download(4, 0x1602, 2, &0x6060_0008u32.to_le_bytes())),
                    read.clone(),
                    rec(0, &download(5, 0x1602, 0, &[2])),
                    read.clone(),
                    rec(0, &download(6, 0x1C12, 1, &0x1602u16.to_le_bytes())),
                    read.clone(),
                    rec(0, &download(7, 0x1C12, 0, &[1])),
                    read.clone(),
                    rec(3, &[0x04]),
                    read.clone(),
                ],
            ),
        ),
        (
            "segmented_upload_eds",
            seed(
                1,
                &[
                    rec(0, &upload(1, 0x1021, 0)),
                    read.clone(),
                    rec(0, &mbx(3, 2, &[0x00, 0x20, 0x60, 0, 0, 0, 0, 0, 0, 0])),
                    read.clone(),
                    rec(0, &mbx(3, 3, &[0x00, 0x20, 0x70, 0, 0, 0, 0, 0, 0, 0])),
                    read.clone(),
                ],
            ),
        ),
        (
            "sdo_info",
            seed(
                0,
                &[
                    rec(0, &mbx(3, 1, &[0x00, 0x80, 0x01, 0, 0, 0, 0x01, 0x00])),
                    rec(1, &[7]),
                    rec(0, &mbx(3, 2, &[0x00, 0x80, 0x05, 0, 0, 0, 0x12, 0x1C, 1, 0x07])),
                    read.clone(),
                ],
            ),
        ),
        (
            "complete_access",
            seed(0, &[rec(0, &mbx(3, 1, &[0x00, 0x20, 0x50, 0x13, 0x1C, 0x00, 0, 0, 0, 0])), read.clone()]),
        ),
        ("foe_setup", {
            let mut wrq = vec![2, 0, 0, 0, 0, 0];
            wrq.extend_from_slice(b"FOESW_A.bin");
            let mut data = vec![3, 0, 1, 0, 0, 0];
            data.extend_from_slice(b"5638\nC400\n0\n");
            seed(0, &[rec(0, &mbx(4, 1, &wrq)), read.clone(), rec(0, &mbx(4, 2, &data)), read.clone()])
        }),
        ("foe_firmware_boot", {
            let mut wrq = vec![2, 0];
            wrq.extend_from_slice(&0x4130_3041u32.to_le_bytes());
            wrq.extend_from_slice(b"FOEFW_FA00H");
            let mut data = vec![3, 0, 1, 0, 0, 0];
            data.extend_from_slice(&[0xA5; 40]);
            seed(
                0,
                &[
                    rec(3, &[0x01]),
                    rec(3, &[0x03]),
                    rec(0, &mbx(4, 1, &wrq)),
                    read.clone(),
                    rec(0, &mbx(4, 2, &data)),
                    rec(2, &[40]),
                    read.clone(),
                    rec(0, &mbx(4, 3, &data)),
                    read.clone(),
                ],
            )
        }),
        (
            "bad_headers",
            seed(
                1,
                &[
                    rec(0, &[0xFF, 0x7F, 0, 0, 0, 0x13]),
                    read.clone(),
                    rec(0, &mbx(5, 2, &[0; 8])),
                    read.clone(),
                    rec(0, &mbx(3, 3, &[])),
                    read.clone(),
                ],
            ),
        ),
        (
            "states_and_errors",
            seed(
                0,
                &[
                    rec(3, &[0x08]),
                    rec(3, &[0x04]),
                    rec(3, &[0x14]),
                    wait.clone(),
                    read.clone(),
                    rec(3, &[0x05]),
                    rec(3, &[0x11]),
                ],
            ),
        ),
    ];
    seeds.sort_by(|a, b| a.0.cmp(b.0));
    for (name, data) in seeds {
        std::fs::write(dir.join(name), data)?;
    }
    Ok(())
}
