//! Whole objects over CoE: the slave's SDO Information (object and entry
//! descriptions: names, data types, bit lengths, access) and complete
//! access.
//!
//! ethercrab 0.7.1 uploads by complete access (`SubIndex::Complete`, from
//! sub 1) but offers only the object lists of SDO Information, so the
//! descriptions go through the mailbox directly: the request is written
//! into the slave's write mailbox and the answer read from its read
//! mailbox, where the slave's SM0/SM1 registers say they are, framed by
//! `drivebus_coe`'s SDO Information codec (the one the slave side
//! answers with). These requests carry mailbox counter 0, which a slave
//! never takes as a repetition (ETG.1000.4 §5.6), so they do not disturb
//! ethercrab's own counting.
//!
//! What the slave offers is what its SII says: General "CoE details"
//! (ETG.2010): bit 1 SDO Information, bit 5 complete access.

use super::{LineMaster, MasterError, Raw, sdo_read};
use drivebus_can::Duration;
pub use drivebus_coe::coe::info_codec::{EntryDescription, ObjectDescription};
use drivebus_coe::coe::info_codec::{InfoRequest, InfoResponse};
use drivebus_coe::coe::split_image;
use drivebus_coe::{MailboxErrorCode, MailboxHeader, MailboxType};
use drivebus_esc::sii::category;
use ethercrab::error::Error;
use ethercrab::{Command, SubDevice, SubDeviceRef, SubIndex};
use std::ops::Deref;

/// SII General "CoE details" bits (ETG.2010 General category, byte 5).
pub mod coe_details {
    /// SDO Information.
    pub const SDO_INFO: u8 = 0x02;
    /// SDO complete access.
    pub const COMPLETE_ACCESS: u8 = 0x20;
}

/// The CoE abort "sub-index does not exist" (a gap in a RECORD).
const NO_SUB_INDEX: u32 = 0x0609_0011;
/// The CoE abort "object does not exist".
const NO_OBJECT: u32 = 0x0602_0000;

/// One entry read from the slave.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Entry {
    /// Sub-index.
    pub sub: u8,
    /// Its SDO Information description, when the slave gave one.
    pub info: Option<EntryDescription<Vec<u8>>>,
    /// The value's bytes.
    pub data: Vec<u8>,
}

/// Where the description of an object read came from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum DescribedBy {
    /// The slave's SDO Information.
    SdoInfo(ObjectDescription<Vec<u8>>),
    /// The slave has no SDO Information (why, in words): the entries are
    /// still to be read with what the caller knows of the object.
    NoSdoInfo(String),
}

/// An object read whole: every entry up to sub 0's count.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ObjectRead {
    /// Object.
    pub index: u16,
    /// Names and types: the slave's, or why there are none.
    pub described: DescribedBy,
    /// The slave announces complete access.
    pub complete_access: bool,
    /// The entries 1.. came in one complete-access upload (else one upload each).
    pub read_complete: bool,
    /// The entries (sub 0 first); empty with [`DescribedBy::NoSdoInfo`].
    pub entries: Vec<Entry>,
}

/// A mailbox's location (SM register contents).
#[derive(Debug, Clone, Copy)]
struct Sm {
    register: u16,
    start: u16,
    len: u16,
}

/// What came back in the read mailbox.
enum Answer {
    /// CoE service data (CoE header first).
    Coe(Vec<u8>),
    /// A mailbox error reply with its detail code.
    MailboxError(u16),
}

impl LineMaster {
    /// The SII General "CoE details" byte of a slave ([`coe_details`]): 0
    /// when its SII has no General category.
    pub async fn coe_details<S: Deref<Target = SubDevice>>(
        &self,
        sd: &SubDeviceRef<'_, S>,
        position: usize,
    ) -> Result<u8, MasterError> {
        let err = |e| MasterError::Ethercrab(format!("slave {position}: reading the SII categories"), e);
        // Categories from word 0x40: type, length in words, data (ETG.1000.6 §5.4).
        let mut word = 0x40u16;
        for _ in 0..64 {
            let mut head = [0u8; 4];
            sd.deref().eeprom_read_raw(&self.md, word, &mut head).await.map_err(err)?;
            let kind = u16::from_le_bytes([head[0], head[1]]);
            let len = u16::from_le_bytes([head[2], head[3]]);
            if kind == category::END {
                break;
            }
            if kind == category::GENERAL {
                let mut g = [0u8; 6];
                sd.deref().eeprom_read_raw(&self.md, word + 2, &mut g).await.map_err(err)?;
                return Ok(g[5]);
            }
            word = match word.checked_add(2).and_then(|w| w.checked_add(len)) {
                Some(w) => w,
                None => break,
            };
        }
        Ok(0)
    }

    /// Where sync manager `n`'s register block is and what it holds.
    async fn sm<S: Deref<Target = SubDevice>>(
        &self,
        sd: &SubDeviceRef<'_, S>,
        n: u16,
    ) -> Result<(Sm, u8), Error> {
        let register = 0x0800 + 8 * n;
        let r: [u8; 8] = sd.register_read(register).await?;
        let sm =
            Sm { register, start: u16::from_le_bytes([r[0], r[1]]), len: u16::from_le_bytes([r[2], r[3]]) };
        // Control: mailbox mode (bits 0-1 = 2), direction in bits 2-3; enabled in bit 0 of 0x0806.
        let enabled = r[6] & 1 != 0 && r[4] & 0x03 == 0x02 && sm.len >= 8;
        Ok((sm, if enabled { (r[4] >> 2) & 0x03 } else { 0xFF }))
    }

    async fn sm_full<S: Deref<Target = SubDevice>>(
        &self,
        sd: &SubDeviceRef<'_, S>,
        sm: Sm,
    ) -> Result<bool, Error> {
        let status: u8 = sd.register_read(sm.register + 5).await?;
        Ok(status & 0x08 != 0)
    }

    /// One CoE request through the mailboxes and its answer (emergencies in
    /// between are passed over).
    async fn exchange<S: Deref<Target = SubDevice>>(
        &self,
        sd: &SubDeviceRef<'_, S>,
        position: usize,
        body: &[u8],
    ) -> Result<Answer, MasterError> {
        let e = |what: &str| {
            let what = format!("slave {position}: SDO Information, {what}");
            move |e| MasterError::Ethercrab(what, e)
        };
        let (mut write, mut read) = (None, None);
        for n in 0..2 {
            match self.sm(sd, n).await.map_err(e("reading the sync managers"))? {
                (sm, 0x01) => write = Some(sm),
                (sm, 0x00) => read = Some(sm),
                _ => {}
            }
        }
        let (Some(write), Some(read)) = (write, read) else {
            return Err(MasterError::Unsupported(format!("slave {position} has no mailbox set up")));
        };
        let addr = sd.configured_address();
        // A stale answer would be taken for ours.
        if self.sm_full(sd, read).await.map_err(e("reading SM1"))? {
            Command::fprd(addr, read.start)
                .receive_slice(&self.md, read.len)
                .await
                .map_err(e("emptying the read mailbox"))?;
        }
        self.poll(sd, write, false).await.map_err(e("waiting for the write mailbox"))?;
        let len = u16::try_from(body.len()).unwrap_or(u16::MAX);
        let header = MailboxHeader {
            length: len,
            address: 0,
            channel: 0,
            priority: 0,
            mailbox_type: MailboxType::Coe,
            counter: 0,
        };
        let mut frame = header.encode().to_vec();
        frame.extend_from_slice(body);
        if frame.len() > usize::from(write.len) {
            return Err(MasterError::Unsupported(format!(
                "slave {position}: its mailbox is too small for the request"
            )));
        }
        // The whole mailbox is written: the last byte hands it to the slave.
        frame.resize(usize::from(write.len), 0);
        Command::fpwr(addr, write.start)
            .send(&self.md, frame.as_slice())
            .await
            .map_err(e("writing the request"))?;
        loop {
            self.poll(sd, read, true).await.map_err(e("waiting for the answer"))?;
            let got = Command::fprd(addr, read.start)
                .receive_slice(&self.md, read.len)
                .await
                .map_err(e("reading the answer"))?;
            let Some(h) = MailboxHeader::decode(&got) else { continue };
            let data = got.get(6..6 + usize::from(h.length)).unwrap_or(&got[6..]);
            match h.mailbox_type {
                MailboxType::Error => {
                    return Ok(Answer::MailboxError(u16::from_le_bytes([
                        data.get(2).copied().unwrap_or(0),
                        data.get(3).copied().unwrap_or(0),
                    ])));
                }
                // A CoE emergency (service 1) is not the answer.
                MailboxType::Coe if data.get(1).is_some_and(|b| b >> 4 == 1) => {}
                MailboxType::Coe => return Ok(Answer::Coe(data.to_vec())),
                _ => {}
            }
        }
    }

    /// Waits (up to 2 s) until mailbox `sm` is full (`full`) or empty.
    async fn poll<S: Deref<Target = SubDevice>>(
        &self,
        sd: &SubDeviceRef<'_, S>,
        sm: Sm,
        full: bool,
    ) -> Result<(), Error> {
        for _ in 0..2000 {
            if self.sm_full(sd, sm).await? == full {
                return Ok(());
            }
            self.pace.sleep(Duration::from_millis(1)).await;
        }
        Err(Error::Timeout(ethercrab::error::TimeoutError::MailboxResponse))
    }

    /// An SDO Information request and its answer: `None` when the slave
    /// does not offer the service.
    async fn info<S: Deref<Target = SubDevice>>(
        &self,
        sd: &SubDeviceRef<'_, S>,
        position: usize,
        req: InfoRequest,
        sub: u8,
    ) -> Result<Option<Vec<u8>>, MasterError> {
        let mut body = Vec::new();
        req.encode(&mut body);
        match self.exchange(sd, position, &body).await? {
            Answer::Coe(b) => Ok(Some(b)),
            Answer::MailboxError(c)
                if c == MailboxErrorCode::SERVICE_NOT_SUPPORTED.0
                    || c == MailboxErrorCode::UNSUPPORTED_PROTOCOL.0 =>
            {
                Ok(None)
            }
            Answer::MailboxError(c) => Err(MasterError::Unsupported(format!(
                "slave {position}: SDO Information on {:04X}h:{sub:02X} answered with mailbox error 0x{c:04X}",
                index_of(req)
            ))),
        }
    }

    /// The slave's Get Object Description of `index`; `None` when it has no
    /// SDO Information. An SDO Info error is [`MasterError::Abort`].
    pub async fn object_description<S: Deref<Target = SubDevice>>(
        &self,
        sd: &SubDeviceRef<'_, S>,
        position: usize,
        index: u16,
    ) -> Result<Option<ObjectDescription<Vec<u8>>>, MasterError> {
        let Some(b) = self.info(sd, position, InfoRequest::ObjectDescription(index), 0).await? else {
            return Ok(None);
        };
        match InfoResponse::decode(&b) {
            Some(InfoResponse::ObjectDescription(d)) if d.index == index => Ok(Some(d.into_owned())),
            Some(InfoResponse::Error(code)) => {
                Err(MasterError::Abort { position, index, sub: 0, write: false, code })
            }
            _ => Err(bad_answer(position, index, 0, &b)),
        }
    }

    /// The slave's Get Entry Description of `index`:`sub` (no optional
    /// fields asked for); `None` when it has no SDO Information.
    pub async fn entry_description<S: Deref<Target = SubDevice>>(
        &self,
        sd: &SubDeviceRef<'_, S>,
        position: usize,
        index: u16,
        sub: u8,
    ) -> Result<Option<EntryDescription<Vec<u8>>>, MasterError> {
        let req = InfoRequest::EntryDescription { index, sub, value_info: 0 };
        let Some(b) = self.info(sd, position, req, sub).await? else {
            return Ok(None);
        };
        match InfoResponse::decode(&b) {
            Some(InfoResponse::EntryDescription(d)) if d.index == index && d.sub == sub => {
                Ok(Some(d.into_owned()))
            }
            Some(InfoResponse::Error(code)) => {
                Err(MasterError::Abort { position, index, sub, write: false, code })
            }
            _ => Err(bad_answer(position, index, sub, &b)),
        }
    }

    /// Reads `index` whole, described by the slave's SDO Information: a VAR
    /// as sub 0, an ARRAY or RECORD as sub 0 and every entry up to its
    /// count (gaps of a RECORD left out), entries 1.. by complete access
    /// where the slave announces it. Without SDO Information (not in the
    /// SII, or refused), [`DescribedBy::NoSdoInfo`] says why and no entry
    /// is read: the caller reads them with [`read_entries`] and its tables.
    pub async fn read_object<S: Deref<Target = SubDevice>>(
        &self,
        sd: &SubDeviceRef<'_, S>,
        position: usize,
        index: u16,
    ) -> Result<ObjectRead, MasterError> {
        let details = self.coe_details(sd, position).await?;
        let complete_access = details & coe_details::COMPLETE_ACCESS != 0;
        let mut read = ObjectRead {
            index,
            described: DescribedBy::NoSdoInfo(String::new()),
            complete_access,
            read_complete: false,
            entries: Vec::new(),
        };
        if details & coe_details::SDO_INFO == 0 {
            read.described =
                DescribedBy::NoSdoInfo("its SII announces no SDO Information (CoE details)".into());
            return Ok(read);
        }
        let Some(object) = self.object_description(sd, position, index).await? else {
            read.described = DescribedBy::NoSdoInfo("it refuses SDO Information (mailbox error)".into());
            return Ok(read);
        };
        let zero = sdo_read(sd, position, index, 0).await?;
        let zero_info = self.entry_description(sd, position, index, 0).await.ok().flatten();
        if object.compound() {
            let n = zero.first().copied().unwrap_or(0).min(object.max_sub);
            let mut layout = Vec::new();
            let mut infos = Vec::new();
            for sub in 1..=n {
                match self.entry_description(sd, position, index, sub).await {
                    Ok(Some(i)) => {
                        layout.push((sub, Some(i.bit_length)));
                        infos.push((sub, i));
                    }
                    // A gap in a RECORD.
                    Err(MasterError::Abort { code: NO_SUB_INDEX | NO_OBJECT, .. }) => {}
                    Ok(None) => layout.push((sub, None)),
                    Err(e) => return Err(e),
                }
            }
            let (values, by_ca) = read_entries(sd, position, index, &layout, complete_access).await?;
            read.read_complete = by_ca;
            read.entries.push(Entry { sub: 0, info: zero_info, data: zero });
            for (sub, data) in values {
                let info = infos.iter().find(|(s, _)| *s == sub).map(|(_, i)| i.clone());
                read.entries.push(Entry { sub, info, data });
            }
        } else {
            read.entries.push(Entry { sub: 0, info: zero_info, data: zero });
        }
        read.described = DescribedBy::SdoInfo(object);
        Ok(read)
    }
}

/// Reads entries 1.. of an ARRAY or RECORD (`layout`: sub-index and bit
/// length where known, in order): in one complete-access upload when
/// `complete_access` and every length is known, the image cut with
/// `drivebus_coe`'s layout; else, or when the slave refuses that upload or
/// its image does not match the layout, one upload per entry (an entry
/// the slave says does not exist is left out). Returns the entries and
/// whether complete access was used.
pub async fn read_entries<S: Deref<Target = SubDevice>>(
    sd: &SubDeviceRef<'_, S>,
    position: usize,
    index: u16,
    layout: &[(u8, Option<u16>)],
    complete_access: bool,
) -> Result<(Vec<(u8, Vec<u8>)>, bool), MasterError> {
    let bits: Option<Vec<(u8, u16)>> = layout.iter().map(|&(s, b)| b.map(|b| (s, b))).collect();
    if let (true, Some(bits)) = (complete_access && !layout.is_empty(), bits)
        && let Ok(image) = sd.sdo_read::<Raw>(index, SubIndex::Complete).await
        && let Some(entries) = split_image(&image.0, 1, &bits)
    {
        return Ok((entries, true));
    }
    let mut out = Vec::new();
    for &(sub, _) in layout {
        match sdo_read(sd, position, index, sub).await {
            Err(MasterError::Abort { code: NO_SUB_INDEX, .. }) => {}
            r => out.push((sub, r?)),
        }
    }
    Ok((out, false))
}

fn index_of(req: InfoRequest) -> u16 {
    match req {
        InfoRequest::ObjectDescription(i) | InfoRequest::EntryDescription { index: i, .. } => i,
        _ => 0,
    }
}

fn bad_answer(position: usize, index: u16, sub: u8, b: &[u8]) -> MasterError {
    MasterError::Unsupported(format!(
        "slave {position}: SDO Information on {index:04X}h:{sub:02X}: an answer that is no description ({} bytes: {:02X?})",
        b.len(),
        &b[..b.len().min(12)]
    ))
}
