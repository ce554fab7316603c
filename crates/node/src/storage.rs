//! Persistent parameter storage behind 1010h/1011h (CiA 301 §7.5.2.13/14).
//!
//! A group (communication, application, manufacturer) is stored as one
//! self-checking image, so a torn or foreign file is detected instead of
//! half-applied.

use alloc::collections::BTreeMap;
use alloc::vec::Vec;
use core::fmt;
use drivebus_od::{ObjectDictionary, PersistGroup};

/// One stored image: a 1010h parameter group, or the LSS configuration.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Slot {
    /// Communication parameters (1010h sub 2).
    Communication,
    /// Application (device profile) parameters (1010h sub 3).
    Application,
    /// Manufacturer parameters (1010h sub 4).
    Manufacturer,
    /// LSS "store configuration": node-ID and bit timing (CiA 305).
    Lss,
}

impl Slot {
    /// The slot of a persistence group (`None` for volatile).
    pub const fn of(group: PersistGroup) -> Option<Slot> {
        match group {
            PersistGroup::Communication => Some(Slot::Communication),
            PersistGroup::Application => Some(Slot::Application),
            PersistGroup::Manufacturer => Some(Slot::Manufacturer),
            PersistGroup::Volatile => None,
        }
    }
}

/// Where stored parameter images live.
pub trait Storage {
    /// Apply every change at once (`Some(image)`: replace the slot's image,
    /// `None`: forget it). Must be atomic as a whole: after a crash either
    /// all changes or none are found, never a mix of groups (a 1010h:01
    /// "save all" writes three groups in one commit).
    fn commit(&mut self, changes: &[(Slot, Option<&[u8]>)]) -> Result<(), StorageError>;
    /// The stored image of `slot`, if any.
    fn load(&mut self, slot: Slot) -> Result<Option<Vec<u8>>, StorageError>;
    /// Replace the stored image of one slot.
    fn save(&mut self, slot: Slot, image: &[u8]) -> Result<(), StorageError> {
        self.commit(&[(slot, Some(image))])
    }
    /// Forget the stored image of one slot (1011h: defaults after the next reset).
    fn erase(&mut self, slot: Slot) -> Result<(), StorageError> {
        self.commit(&[(slot, None)])
    }
}

/// A storage failure (reported to the SDO client as `0606 0000`).
#[derive(Debug)]
pub enum StorageError {
    /// The medium failed.
    #[cfg(feature = "std")]
    Io(std::io::Error),
    /// Storage is not available for this group.
    Unsupported,
    /// The stored data is damaged (checksum or structure; byte offset).
    Corrupt(usize),
}

impl fmt::Display for StorageError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            #[cfg(feature = "std")]
            StorageError::Io(e) => write!(f, "storage I/O error: {e}"),
            StorageError::Unsupported => f.write_str("storage not supported"),
            StorageError::Corrupt(at) => write!(f, "stored parameters damaged at byte {at}"),
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for StorageError {}

#[cfg(feature = "std")]
impl From<std::io::Error> for StorageError {
    fn from(e: std::io::Error) -> Self {
        StorageError::Io(e)
    }
}

/// Storage in memory (tests, `no_std` targets without flash driver).
#[derive(Clone, Debug, Default)]
pub struct MemoryStorage {
    images: BTreeMap<u8, Vec<u8>>,
}

impl MemoryStorage {
    /// Empty storage.
    pub fn new() -> Self {
        Self::default()
    }
}

impl Storage for MemoryStorage {
    fn commit(&mut self, changes: &[(Slot, Option<&[u8]>)]) -> Result<(), StorageError> {
        for &(slot, image) in changes {
            match image {
                Some(img) => self.images.insert(slot as u8, img.to_vec()),
                None => self.images.remove(&(slot as u8)),
            };
        }
        Ok(())
    }
    fn load(&mut self, slot: Slot) -> Result<Option<Vec<u8>>, StorageError> {
        Ok(self.images.get(&(slot as u8)).cloned())
    }
}

const MAGIC: &[u8; 4] = b"DBPS";
const VERSION: u8 = 1;
const CRC: crc::Crc<u16> = crc::Crc::<u16>::new(&crc::CRC_16_XMODEM);

/// Serialise every sub-object of `group`: `DBPS`, version, group, count,
/// then `(index u16, sub u8, len u32, bytes)` records, then a CRC-16.
pub fn encode_image(od: &ObjectDictionary, group: PersistGroup) -> Vec<u8> {
    let mut out = Vec::new();
    out.extend_from_slice(MAGIC);
    out.push(VERSION);
    out.push(group as u8);
    out.extend_from_slice(&[0; 4]);
    let mut n: u32 = 0;
    for (index, sub, bytes) in od.persistent_values(group) {
        out.extend_from_slice(&index.to_le_bytes());
        out.push(sub);
        out.extend_from_slice(&(bytes.len() as u32).to_le_bytes());
        out.extend_from_slice(bytes);
        n += 1;
    }
    out[6..10].copy_from_slice(&n.to_le_bytes());
    let crc = CRC.checksum(&out);
    out.extend_from_slice(&crc.to_le_bytes());
    out
}

/// Why a stored image was not applied.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ImageError {
    /// Not an image of this format (byte offset of the mismatch).
    BadHeader(usize),
    /// The checksum does not match: torn write or corruption.
    BadChecksum,
    /// A record runs past the end (byte offset of the record).
    Truncated(usize),
    /// The image belongs to another group.
    WrongGroup,
}

impl fmt::Display for ImageError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ImageError::BadHeader(o) => write!(f, "not a parameter image (offset {o})"),
            ImageError::BadChecksum => f.write_str("parameter image checksum mismatch"),
            ImageError::Truncated(o) => write!(f, "parameter image truncated at offset {o}"),
            ImageError::WrongGroup => f.write_str("parameter image of another group"),
        }
    }
}

/// Apply a stored image to the dictionary. Entries that no longer exist or
/// whose value no longer fits (type, limits) are skipped and counted: a
/// firmware update must not brick a node. Returns `(applied, skipped)`.
pub fn apply_image(
    od: &mut ObjectDictionary,
    group: PersistGroup,
    image: &[u8],
) -> Result<(usize, usize), ImageError> {
    if image.len() < 12 || &image[..4] != MAGIC {
        return Err(ImageError::BadHeader(0));
    }
    if image[4] != VERSION {
        return Err(ImageError::BadHeader(4));
    }
    let (body, crc) = image.split_at(image.len() - 2);
    if CRC.checksum(body) != u16::from_le_bytes([crc[0], crc[1]]) {
        return Err(ImageError::BadChecksum);
    }
    if body[5] != group as u8 {
        return Err(ImageError::WrongGroup);
    }
    let count = u32::from_le_bytes([body[6], body[7], body[8], body[9]]);
    let mut at = 10;
    let (mut applied, mut skipped) = (0, 0);
    for _ in 0..count {
        let head = body.get(at..at + 7).ok_or(ImageError::Truncated(at))?;
        let index = u16::from_le_bytes([head[0], head[1]]);
        let sub = head[2];
        let len = u32::from_le_bytes([head[3], head[4], head[5], head[6]]) as usize;
        let data = body.get(at + 7..at + 7 + len).ok_or(ImageError::Truncated(at))?;
        at += 7 + len;
        match od.find(index, sub) {
            Ok(r) if od.entry(r).persist == group && od.entry(r).validate(data).is_ok() => {
                od.set_raw(r, data);
                applied += 1;
            }
            _ => skipped += 1,
        }
    }
    if at != body.len() {
        return Err(ImageError::Truncated(at));
    }
    Ok((applied, skipped))
}

/// Parameter images of every slot in one file, `parameters.bin`,
/// replaced as a whole (temporary file, fsync, rename, fsync of the
/// directory): a save of several groups is one rename, so a crash at any
/// point leaves the complete old set or the complete new set.
///
/// Directories written by earlier versions (one `<group>.params` file per
/// slot) are read as long as no `parameters.bin` exists; the first commit
/// replaces them.
#[cfg(feature = "std")]
#[derive(Clone, Debug)]
pub struct FileStorage {
    dir: std::path::PathBuf,
}

/// `parameters.bin`: magic, version, record count, records
/// `(slot u8, len u32, image)`, CRC-32 of everything before it.
#[cfg(feature = "std")]
const SET_MAGIC: &[u8; 4] = b"DBST";
#[cfg(feature = "std")]
const SET_VERSION: u8 = 1;
#[cfg(feature = "std")]
const SET_CRC: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISCSI);
#[cfg(feature = "std")]
const ALL_SLOTS: [Slot; 4] = [Slot::Communication, Slot::Application, Slot::Manufacturer, Slot::Lss];

#[cfg(feature = "std")]
impl FileStorage {
    /// Store images under `dir` (created if missing).
    pub fn new(dir: impl Into<std::path::PathBuf>) -> std::io::Result<Self> {
        let dir = dir.into();
        std::fs::create_dir_all(&dir)?;
        Ok(FileStorage { dir })
    }

    fn set_path(&self) -> std::path::PathBuf {
        self.dir.join("parameters.bin")
    }

    fn legacy_path(&self, slot: Slot) -> std::path::PathBuf {
        let name = match slot {
            Slot::Communication => "communication.params",
            Slot::Application => "application.params",
            Slot::Manufacturer => "manufacturer.params",
            Slot::Lss => "lss.params",
        };
        self.dir.join(name)
    }

    /// Every stored image, from `parameters.bin` or the legacy files.
    fn read_set(&self) -> Result<BTreeMap<u8, Vec<u8>>, StorageError> {
        match std::fs::read(self.set_path()) {
            Ok(bytes) => decode_set(&bytes),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                let mut set = BTreeMap::new();
                for slot in ALL_SLOTS {
                    match std::fs::read(self.legacy_path(slot)) {
                        Ok(b) => {
                            set.insert(slot as u8, b);
                        }
                        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
                        Err(e) => return Err(e.into()),
                    }
                }
                Ok(set)
            }
            Err(e) => Err(e.into()),
        }
    }
}

#[cfg(feature = "std")]
fn encode_set(set: &BTreeMap<u8, Vec<u8>>) -> Vec<u8> {
    let mut out = Vec::new();
    out.extend_from_slice(SET_MAGIC);
    out.push(SET_VERSION);
    out.push(set.len() as u8);
    for (slot, image) in set {
        out.push(*slot);
        out.extend_from_slice(&(image.len() as u32).to_le_bytes());
        out.extend_from_slice(image);
    }
    let crc = SET_CRC.checksum(&out);
    out.extend_from_slice(&crc.to_le_bytes());
    out
}

#[cfg(feature = "std")]
fn decode_set(bytes: &[u8]) -> Result<BTreeMap<u8, Vec<u8>>, StorageError> {
    if bytes.len() < 10 || &bytes[..4] != SET_MAGIC || bytes[4] != SET_VERSION {
        return Err(StorageError::Corrupt(0));
    }
    let (body, crc) = bytes.split_at(bytes.len() - 4);
    if SET_CRC.checksum(body) != u32::from_le_bytes([crc[0], crc[1], crc[2], crc[3]]) {
        return Err(StorageError::Corrupt(body.len()));
    }
    let mut set = BTreeMap::new();
    let mut at = 6;
    for _ in 0..body[5] {
        let head = body.get(at..at + 5).ok_or(StorageError::Corrupt(at))?;
        let len = u32::from_le_bytes([head[1], head[2], head[3], head[4]]) as usize;
        let image = body.get(at + 5..at + 5 + len).ok_or(StorageError::Corrupt(at))?;
        set.insert(head[0], image.to_vec());
        at += 5 + len;
    }
    if at != body.len() {
        return Err(StorageError::Corrupt(at));
    }
    Ok(set)
}

#[cfg(feature = "std")]
impl Storage for FileStorage {
    fn commit(&mut self, changes: &[(Slot, Option<&[u8]>)]) -> Result<(), StorageError> {
        use std::io::Write;
        let mut set = match self.read_set() {
            Ok(set) => set,
            // A damaged set (which a rename-based commit cannot produce,
            // but a failing medium can) is replaced rather than blocking
            // every later save.
            Err(StorageError::Corrupt(_)) => BTreeMap::new(),
            Err(e) => return Err(e),
        };
        for &(slot, image) in changes {
            match image {
                Some(img) => set.insert(slot as u8, img.to_vec()),
                None => set.remove(&(slot as u8)),
            };
        }
        let path = self.set_path();
        let tmp = path.with_extension("tmp");
        {
            let mut f = std::fs::File::create(&tmp)?;
            f.write_all(&encode_set(&set))?;
            f.sync_all()?;
        }
        std::fs::rename(&tmp, &path)?;
        std::fs::File::open(&self.dir)?.sync_all()?;
        // The set is now authoritative: legacy files would only mislead a reader.
        for slot in ALL_SLOTS {
            match std::fs::remove_file(self.legacy_path(slot)) {
                Err(e) if e.kind() != std::io::ErrorKind::NotFound => return Err(e.into()),
                _ => {}
            }
        }
        Ok(())
    }
    fn load(&mut self, slot: Slot) -> Result<Option<Vec<u8>>, StorageError> {
        Ok(self.read_set()?.remove(&(slot as u8)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use drivebus_od::{Access, DataType, NoHooks, Object, Value};

    fn od() -> ObjectDictionary {
        let mut od = ObjectDictionary::new();
        od.insert(Object::var(
            0x1017,
            "Producer heartbeat time",
            DataType::Unsigned16,
            Access::Rw,
            Value::U16(0),
        ));
        od.insert(Object::var(0x6060, "Modes of operation", DataType::Integer8, Access::Rw, Value::I8(0)));
        od.insert(Object::var(0x2001, "Name", DataType::VisibleString, Access::Rw, Value::Str("abc".into())));
        od
    }

    #[test]
    fn image_round_trip_per_group() {
        let mut a = od();
        a.write(&mut NoHooks, 0x1017, 0, &500u16.to_le_bytes()).unwrap();
        a.write(&mut NoHooks, 0x2001, 0, b"longer name").unwrap();
        let comm = encode_image(&a, PersistGroup::Communication);
        let mfr = encode_image(&a, PersistGroup::Manufacturer);
        let mut b = od();
        assert_eq!(apply_image(&mut b, PersistGroup::Communication, &comm), Ok((1, 0)));
        assert_eq!(apply_image(&mut b, PersistGroup::Manufacturer, &mfr), Ok((1, 0)));
        assert_eq!(b.get_u64(0x1017, 0), Some(500));
        assert_eq!(b.get(0x2001, 0).unwrap().bytes(), b"longer name");
        assert_eq!(apply_image(&mut b, PersistGroup::Application, &comm), Err(ImageError::WrongGroup));
    }

    #[test]
    fn corrupt_images_are_refused_not_applied() {
        let a = od();
        let img = encode_image(&a, PersistGroup::Communication);
        let mut b = od();
        let mut flipped = img.clone();
        flipped[11] ^= 1;
        assert_eq!(apply_image(&mut b, PersistGroup::Communication, &flipped), Err(ImageError::BadChecksum));
        assert_eq!(
            apply_image(&mut b, PersistGroup::Communication, &img[..5]),
            Err(ImageError::BadHeader(0))
        );
        assert_eq!(
            apply_image(&mut b, PersistGroup::Communication, b"XXXXXXXXXXXXXX"),
            Err(ImageError::BadHeader(0))
        );
    }

    #[test]
    fn file_storage_replaces_atomically() {
        let dir = tempfile::tempdir().unwrap();
        let mut s = FileStorage::new(dir.path()).unwrap();
        assert!(s.load(Slot::Communication).unwrap().is_none());
        s.save(Slot::Communication, b"one").unwrap();
        s.save(Slot::Communication, b"two").unwrap();
        assert_eq!(s.load(Slot::Communication).unwrap().as_deref(), Some(&b"two"[..]));
        // A stale temporary file from a crash mid-save does not shadow the image.
        std::fs::write(dir.path().join("parameters.tmp"), b"torn").unwrap();
        assert_eq!(s.load(Slot::Communication).unwrap().as_deref(), Some(&b"two"[..]));
        s.erase(Slot::Communication).unwrap();
        assert!(s.load(Slot::Communication).unwrap().is_none());
    }

    #[test]
    fn file_storage_commits_several_slots_at_once_and_reads_legacy_files() {
        let dir = tempfile::tempdir().unwrap();
        // A directory written by the one-file-per-group version.
        std::fs::write(dir.path().join("communication.params"), b"old comm").unwrap();
        std::fs::write(dir.path().join("lss.params"), [5, 0]).unwrap();
        let mut s = FileStorage::new(dir.path()).unwrap();
        assert_eq!(s.load(Slot::Communication).unwrap().as_deref(), Some(&b"old comm"[..]));
        s.commit(&[(Slot::Communication, Some(b"comm")), (Slot::Application, Some(b"app"))]).unwrap();
        assert!(!dir.path().join("communication.params").exists(), "legacy files go after the first commit");
        assert_eq!(s.load(Slot::Communication).unwrap().as_deref(), Some(&b"comm"[..]));
        assert_eq!(s.load(Slot::Application).unwrap().as_deref(), Some(&b"app"[..]));
        assert_eq!(s.load(Slot::Lss).unwrap().as_deref(), Some(&[5u8, 0][..]), "untouched slots are kept");
        s.commit(&[(Slot::Communication, None), (Slot::Application, None)]).unwrap();
        assert!(
            s.load(Slot::Communication).unwrap().is_none() && s.load(Slot::Application).unwrap().is_none()
        );
        assert!(s.load(Slot::Lss).unwrap().is_some());
    }

    #[test]
    fn damaged_parameter_set_is_reported_then_replaced() {
        let dir = tempfile::tempdir().unwrap();
        let mut s = FileStorage::new(dir.path()).unwrap();
        s.save(Slot::Application, b"app").unwrap();
        let path = dir.path().join("parameters.bin");
        let mut bytes = std::fs::read(&path).unwrap();
        bytes[8] ^= 0x40;
        std::fs::write(&path, &bytes).unwrap();
        assert!(matches!(s.load(Slot::Application), Err(StorageError::Corrupt(_))));
        s.save(Slot::Communication, b"comm").unwrap();
        assert_eq!(s.load(Slot::Communication).unwrap().as_deref(), Some(&b"comm"[..]));
    }

    proptest::proptest! {
        #[test]
        fn garbage_parameter_sets_never_panic(bytes in proptest::collection::vec(proptest::num::u8::ANY, 0..64)) {
            let _ = decode_set(&bytes);
        }

        #[test]
        fn garbage_images_never_panic(bytes in proptest::collection::vec(proptest::num::u8::ANY, 0..64)) {
            let mut b = od();
            let _ = apply_image(&mut b, PersistGroup::Communication, &bytes);
        }
    }
}
