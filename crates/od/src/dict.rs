//! The object dictionary: objects, sub-objects, lookup and checked access.

use crate::bytes::ValueBytes;
use crate::owner::{ObjectHooks, Owner, Target, WriteOutcome};
use crate::types::{check_len, compare_le};
use crate::{Access, DataType, ObjectCode, PersistGroup, SdoAbort, Value};
use alloc::borrow::Cow;
use alloc::vec::Vec;
use core::cmp::Ordering;

/// A stable handle to one sub-object: positions in the dictionary, resolved
/// once (e.g. when a PDO is mapped) so the frame path never searches.
/// Valid until an object is inserted or removed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct EntryRef {
    obj: u32,
    sub: u32,
}

/// One sub-object (a VAR is an object with a single sub-object 0).
#[derive(Debug, PartialEq)]
pub struct SubObject {
    /// Sub-index.
    pub sub: u8,
    /// Parameter name (CiA 306 `ParameterName`).
    pub name: Cow<'static, str>,
    /// Data type.
    pub data_type: DataType,
    /// Access type.
    pub access: Access,
    /// May be mapped into a PDO (direction follows `access`).
    pub pdo_mappable: bool,
    /// Lowest allowed value (numeric types), little-endian.
    pub low_limit: Option<Vec<u8>>,
    /// Highest allowed value (numeric types), little-endian.
    pub high_limit: Option<Vec<u8>>,
    /// Value after reset / restore defaults, little-endian.
    pub default: Vec<u8>,
    /// Store/restore group for 1010h/1011h.
    pub persist: PersistGroup,
    /// Largest byte length a variable-size value may take (`None`: unbounded).
    pub max_len: Option<usize>,
    /// Who checks and applies writes (see [`crate::owner`]); `NONE`: the
    /// dictionary stores them itself.
    pub owner: Owner,
    /// The owner refreshes the value before every read ([`ObjectHooks::on_read`]).
    pub live: bool,
    /// The application sees writes first and may veto them, though another
    /// owner holds the entry (a drive refusing a 1010h store while enabled).
    pub watched: bool,
    /// Changes of the value count in [`ObjectDictionary::generation`]
    /// (default: yes). A device unmarks what no poller watches, so writes
    /// to those entries do not wake it (only entries mapped into
    /// event-driven TPDOs stay marked in a node).
    pub marked: bool,
    /// The DefaultValue text contained `$NODEID` (CiA 306): kept for EDS export.
    pub node_id_relative: bool,
    value: ValueBytes,
}

impl SubObject {
    /// A sub-object with its default value; persistence by index range is set
    /// when it is inserted into an [`Object`].
    pub fn new(
        sub: u8,
        name: impl Into<Cow<'static, str>>,
        data_type: DataType,
        access: Access,
        default: Value,
    ) -> SubObject {
        let bytes = default.encode(data_type).unwrap_or_else(|_| match data_type.fixed_size() {
            Some(n) => alloc::vec![0; n],
            None => Vec::new(),
        });
        SubObject::from_bytes(sub, name, data_type, access, bytes)
    }

    /// A sub-object whose default is given as its raw encoding.
    pub fn from_bytes(
        sub: u8,
        name: impl Into<Cow<'static, str>>,
        data_type: DataType,
        access: Access,
        default: Vec<u8>,
    ) -> SubObject {
        SubObject {
            sub,
            name: name.into(),
            data_type,
            access,
            pdo_mappable: false,
            low_limit: None,
            high_limit: None,
            value: ValueBytes::from_slice(&default),
            default,
            persist: PersistGroup::Volatile,
            max_len: None,
            owner: Owner::NONE,
            live: false,
            watched: false,
            marked: true,
            node_id_relative: false,
        }
    }

    /// Mark PDO-mappable.
    pub fn mappable(mut self) -> Self {
        self.pdo_mappable = true;
        self
    }
    /// Set numeric limits (inclusive).
    pub fn limits(mut self, low: Value, high: Value) -> Self {
        self.low_limit = low.encode(self.data_type).ok();
        self.high_limit = high.encode(self.data_type).ok();
        self
    }
    /// Owned by whoever installs it, reads and writes going through the
    /// hooks ([`Owner::HOOKED`], live): the way a service marks the
    /// communication objects it must check, apply or refresh.
    pub fn hooked(mut self) -> Self {
        self.owner = Owner::HOOKED;
        self.live = true;
        self
    }
    /// Owned by `owner` (writes checked and applied by it).
    pub fn owned(mut self, owner: Owner) -> Self {
        self.owner = owner;
        self
    }
    /// Refreshed by its owner before every read.
    pub fn live(mut self) -> Self {
        self.live = true;
        self
    }
    /// Reads or writes leave the fast path (an owner, a watcher or a live
    /// value): a raw copy is not equivalent to a checked access.
    #[inline]
    pub fn is_hooked(&self) -> bool {
        self.owner != Owner::NONE || self.watched || self.live
    }
    /// Override the persistence group.
    pub fn persist(mut self, group: PersistGroup) -> Self {
        self.persist = group;
        self
    }
    /// Bound the length of a variable-size value.
    pub fn max_len(mut self, n: usize) -> Self {
        self.max_len = Some(n);
        self
    }

    /// The current value's encoding.
    #[inline]
    pub fn bytes(&self) -> &[u8] {
        &self.value
    }
    /// The current value, decoded.
    pub fn value(&self) -> Value {
        Value::decode(self.data_type, &self.value).unwrap_or(Value::Bytes(self.value.to_vec()))
    }
    /// The default value, decoded.
    pub fn default_value(&self) -> Value {
        Value::decode(self.data_type, &self.default).unwrap_or(Value::Bytes(self.default.clone()))
    }
    /// Size in bits when mapped into a PDO (`None` for variable-size types).
    pub fn bit_len(&self) -> Option<u32> {
        self.data_type
            .fixed_size()
            .map(|n| if self.data_type == DataType::Boolean { 1 } else { 8 * n as u32 })
    }
    /// May be mapped into a TPDO.
    pub fn tpdo_mappable(&self) -> bool {
        self.pdo_mappable && self.access.readable()
    }
    /// May be mapped into an RPDO.
    pub fn rpdo_mappable(&self) -> bool {
        self.pdo_mappable && self.access.writable()
    }

    /// Check `data` against type, length and limits (no access check).
    #[inline]
    pub fn validate(&self, data: &[u8]) -> Result<(), SdoAbort> {
        check_len(self.data_type, data.len())?;
        if let Some(max) = self.max_len
            && data.len() > max
        {
            return Err(SdoAbort::DATA_TOO_LONG);
        }
        if self.data_type == DataType::Boolean && data[0] > 1 {
            return Err(SdoAbort::INVALID_VALUE);
        }
        if let Some(lo) = &self.low_limit
            && compare_le(self.data_type, data, lo) == Some(Ordering::Less)
        {
            return Err(SdoAbort::VALUE_TOO_LOW);
        }
        if let Some(hi) = &self.high_limit
            && compare_le(self.data_type, data, hi) == Some(Ordering::Greater)
        {
            return Err(SdoAbort::VALUE_TOO_HIGH);
        }
        Ok(())
    }
}

/// One object: index, code, name and its sub-objects (sorted by sub-index).
#[derive(Debug, PartialEq)]
pub struct Object {
    /// Index.
    pub index: u16,
    /// VAR, ARRAY, RECORD, DOMAIN ...
    pub code: ObjectCode,
    /// Object name.
    pub name: Cow<'static, str>,
    /// CiA 306 `ObjFlags`.
    pub flags: u32,
    subs: Vec<SubObject>,
}

impl Object {
    /// A VAR object (single sub-object 0).
    pub fn var(
        index: u16,
        name: impl Into<Cow<'static, str>>,
        data_type: DataType,
        access: Access,
        default: Value,
    ) -> Object {
        let name = name.into();
        let code = if data_type == DataType::Domain { ObjectCode::Domain } else { ObjectCode::Var };
        Object::with_code(index, code, name.clone())
            .with_sub(SubObject::new(0, name, data_type, access, default))
    }

    /// An empty object of the given code; add sub-objects with [`Object::with_sub`].
    pub fn with_code(index: u16, code: ObjectCode, name: impl Into<Cow<'static, str>>) -> Object {
        Object { index, code, name: name.into(), flags: 0, subs: Vec::new() }
    }

    /// A RECORD with sub 0 "Highest sub-index supported" (filled in as subs are added).
    pub fn record(index: u16, name: impl Into<Cow<'static, str>>) -> Object {
        Object::with_code(index, ObjectCode::Record, name).with_sub(SubObject::new(
            0,
            "Highest sub-index supported",
            DataType::Unsigned8,
            Access::Const,
            Value::U8(0),
        ))
    }

    /// An ARRAY of `n` elements of one type, sub 0 holding `n` (read-only).
    pub fn array(
        index: u16,
        name: impl Into<Cow<'static, str>>,
        data_type: DataType,
        access: Access,
        n: u8,
        default: Value,
    ) -> Object {
        let name = name.into();
        let mut o = Object::with_code(index, ObjectCode::Array, name.clone()).with_sub(SubObject::new(
            0,
            "Highest sub-index supported",
            DataType::Unsigned8,
            Access::Const,
            Value::U8(n),
        ));
        for i in 1..=n {
            o = o.with_sub(SubObject::new(
                i,
                alloc::format!("{name} {i}"),
                data_type,
                access,
                default.clone(),
            ));
        }
        o
    }

    /// Add (or replace) a sub-object. For RECORD/ARRAY objects whose sub 0 is
    /// constant, sub 0 is kept equal to the highest sub-index.
    pub fn with_sub(mut self, mut s: SubObject) -> Object {
        if s.persist == PersistGroup::Volatile && s.access.writable() {
            s.persist = PersistGroup::for_index(self.index);
        }
        // Builders add sub-objects in order: appending needs no search.
        if self.subs.last().is_none_or(|x| x.sub < s.sub) {
            self.subs.push(s);
        } else {
            match self.subs.binary_search_by_key(&s.sub, |x| x.sub) {
                Ok(i) => self.subs[i] = s,
                Err(i) => self.subs.insert(i, s),
            }
        }
        let highest = self.subs.last().map_or(0, |x| x.sub);
        if self.code != ObjectCode::Var
            && self.code != ObjectCode::Domain
            && let Some(s0) = self.subs.first_mut()
            && s0.sub == 0
            && s0.access == Access::Const
            && s0.data_type == DataType::Unsigned8
        {
            s0.value = ValueBytes::from_slice(&[highest]);
            s0.default = alloc::vec![highest];
        }
        self
    }

    /// Modify the most recently added sub-object (builder convenience).
    pub fn last_sub_mut(&mut self) -> Option<&mut SubObject> {
        self.subs.last_mut()
    }

    /// Sub-objects in sub-index order.
    pub fn subs(&self) -> &[SubObject] {
        &self.subs
    }
    /// Mutable sub-objects (the value is only changed through checked paths).
    pub fn subs_mut(&mut self) -> &mut [SubObject] {
        &mut self.subs
    }
    /// One sub-object.
    pub fn get(&self, sub: u8) -> Option<&SubObject> {
        self.subs.binary_search_by_key(&sub, |x| x.sub).ok().map(|i| &self.subs[i])
    }
}

/// A runtime-built object dictionary, objects sorted by index.
#[derive(Debug, Default)]
pub struct ObjectDictionary {
    objects: Vec<Object>,
    /// `objects[i].index`, packed: the lookup walks 2-byte keys instead of
    /// 64-byte objects, and does so without data-dependent branches.
    keys: Vec<u16>,
    generation: u64,
}

// The Clone impls (buffer-reusing `clone_from`) are in `dict/clone.rs`.
mod clone;

/// Position of `key` in the sorted `keys`, branch-free (a mispredicted
/// branch per probe costs more than the whole search otherwise).
#[inline]
fn search(keys: &[u16], key: u16) -> Result<usize, usize> {
    let mut base = 0usize;
    let mut size = keys.len();
    if size == 0 {
        return Err(0);
    }
    while size > 1 {
        let half = size / 2;
        let mid = base + half;
        // Compiles to a conditional move.
        base = if keys[mid] <= key { mid } else { base };
        size -= half;
    }
    if keys[base] == key { Ok(base) } else { Err(base + usize::from(keys[base] < key)) }
}

/// Copy of a small value with constant-size moves (no `memmove` call).
#[inline]
fn copy_small(dst: &mut [u8], src: &[u8]) {
    match (dst.len(), src.len()) {
        (1, 1) => dst[0] = src[0],
        (2, 2) => dst.copy_from_slice(&src[..2]),
        (4, 4) => dst.copy_from_slice(&src[..4]),
        (8, 8) => dst.copy_from_slice(&src[..8]),
        _ => {
            let n = dst.len().min(src.len());
            dst[..n].copy_from_slice(&src[..n]);
        }
    }
}

/// Equality of small values without a `memcmp` call.
#[inline]
fn same_bytes(a: &[u8], b: &[u8]) -> bool {
    if a.len() != b.len() {
        return false;
    }
    if a.len() <= 8 {
        let (mut x, mut y) = ([0u8; 8], [0u8; 8]);
        x[..a.len()].copy_from_slice(a);
        y[..b.len()].copy_from_slice(b);
        return u64::from_le_bytes(x) == u64::from_le_bytes(y);
    }
    a == b
}

/// Two dictionaries are equal when their objects are; the change counter is
/// bookkeeping, not content.
impl PartialEq for ObjectDictionary {
    fn eq(&self, other: &Self) -> bool {
        self.objects == other.objects
    }
}

impl ObjectDictionary {
    /// An empty dictionary.
    pub fn new() -> Self {
        Self::default()
    }

    /// Insert or replace an object. Invalidates every [`EntryRef`].
    pub fn insert(&mut self, obj: Object) {
        match search(&self.keys, obj.index) {
            Ok(i) => self.objects[i] = obj,
            Err(i) => {
                self.keys.insert(i, obj.index);
                self.objects.insert(i, obj);
            }
        }
        self.bump_all();
    }

    /// Remove an object. Invalidates every [`EntryRef`].
    pub fn remove(&mut self, index: u16) -> Option<Object> {
        let i = search(&self.keys, index).ok()?;
        self.bump_all();
        self.keys.remove(i);
        Some(self.objects.remove(i))
    }

    /// All objects in index order.
    pub fn objects(&self) -> &[Object] {
        &self.objects
    }
    /// One object.
    pub fn object(&self, index: u16) -> Option<&Object> {
        search(&self.keys, index).ok().map(|i| &self.objects[i])
    }
    /// One object, mutable (for builders; values change through checked
    /// paths). Changing its `index` is not supported: re-insert instead.
    pub fn object_mut(&mut self, index: u16) -> Option<&mut Object> {
        search(&self.keys, index).ok().map(move |i| &mut self.objects[i])
    }

    /// Counter bumped by every change of a [`SubObject::marked`] value
    /// (every value, unless a device unmarked some) and of the structure.
    /// Lets a poller (change-of-state TPDOs) skip work when nothing it
    /// watches was written.
    #[inline]
    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// Marks or unmarks one entry (see [`SubObject::marked`]).
    pub fn set_marked(&mut self, r: EntryRef, on: bool) {
        self.objects[r.obj as usize].subs[r.sub as usize].marked = on;
    }

    /// Visits every sub-object mutably, with its object's index, in index
    /// order: a pass over the whole dictionary without collecting keys
    /// first (e.g. resolving owners after a batch of inserts).
    pub fn for_each_sub_mut(&mut self, mut f: impl FnMut(u16, &mut SubObject)) {
        for o in &mut self.objects {
            let index = o.index;
            for s in &mut o.subs {
                f(index, s);
            }
        }
    }

    /// Marks or unmarks every entry.
    pub fn mark_all(&mut self, on: bool) {
        for o in &mut self.objects {
            for s in &mut o.subs {
                s.marked = on;
            }
        }
    }

    /// A change of the structure (or of an unknown set of values).
    #[inline]
    fn bump_all(&mut self) {
        self.generation = self.generation.wrapping_add(1);
    }

    /// Resolve `(index, sub)`: `0602 0000` or `0609 0011` if absent.
    #[inline]
    pub fn find(&self, index: u16, sub: u8) -> Result<EntryRef, SdoAbort> {
        let obj = search(&self.keys, index).map_err(|_| SdoAbort::NO_OBJECT)?;
        let subs = &self.objects[obj].subs;
        // Sub-objects are usually dense from 0: try the direct slot first.
        let pos = match subs.get(sub as usize) {
            Some(s) if s.sub == sub => sub as usize,
            _ => subs.binary_search_by_key(&sub, |s| s.sub).map_err(|_| SdoAbort::NO_SUB_INDEX)?,
        };
        Ok(EntryRef { obj: obj as u32, sub: pos as u32 })
    }

    /// The sub-object behind a handle.
    #[inline]
    pub fn entry(&self, r: EntryRef) -> &SubObject {
        &self.objects[r.obj as usize].subs[r.sub as usize]
    }
    /// The object index of a handle.
    #[inline]
    pub fn index_of(&self, r: EntryRef) -> (u16, u8) {
        let o = &self.objects[r.obj as usize];
        (o.index, o.subs[r.sub as usize].sub)
    }
    /// The sub-object at `(index, sub)`.
    pub fn get(&self, index: u16, sub: u8) -> Option<&SubObject> {
        self.find(index, sub).ok().map(|r| self.entry(r))
    }
    /// Mutable metadata of a sub-object (name, limits, access...). Use the
    /// `set_*`/`write*` paths to change its value.
    pub fn get_mut(&mut self, index: u16, sub: u8) -> Option<&mut SubObject> {
        let r = self.find(index, sub).ok()?;
        self.bump_all();
        Some(&mut self.objects[r.obj as usize].subs[r.sub as usize])
    }

    /// The stored bytes behind a handle (no hook, no access check).
    #[inline]
    pub fn bytes(&self, r: EntryRef) -> &[u8] {
        &self.entry(r).value
    }

    /// Overwrite the stored bytes without checks (the application pushing a
    /// live value, a service updating its own object). The caller owns the
    /// invariant that `data` is a valid encoding for the type.
    #[inline(always)]
    pub fn set_raw(&mut self, r: EntryRef, data: &[u8]) {
        let s = &mut self.objects[r.obj as usize].subs[r.sub as usize];
        // The usual numeric sizes: one word compare and store.
        if let Some(changed) = s.value.set_inline(data) {
            self.generation = self.generation.wrapping_add(u64::from(changed & s.marked));
            return;
        }
        self.set_raw_slow(r, data);
    }

    /// [`set_raw`](Self::set_raw) for heap values and length changes.
    #[inline(never)]
    fn set_raw_slow(&mut self, r: EntryRef, data: &[u8]) {
        let s = &mut self.objects[r.obj as usize].subs[r.sub as usize];
        if !same_bytes(&s.value, data) {
            if s.value.len() == data.len() {
                copy_small(s.value.as_mut_slice(), data);
            } else {
                s.value.set(data);
            }
            self.generation = self.generation.wrapping_add(u64::from(s.marked));
        }
    }

    /// Stores the low bytes of `w`, as many as the entry holds, if it holds
    /// at most `max` bytes inline: `set_raw(r, &w.to_le_bytes()[..len])`
    /// as one masked compare and store (live values pushed every control
    /// period). `false`, nothing stored, for a longer entry.
    #[inline(always)]
    pub fn set_low(&mut self, r: EntryRef, w: u64, max: usize) -> bool {
        let s = &mut self.objects[r.obj as usize].subs[r.sub as usize];
        match s.value.set_low(w, max) {
            Some(changed) => {
                self.generation = self.generation.wrapping_add(u64::from(changed & s.marked));
                true
            }
            None => false,
        }
    }

    /// The value of a fixed-size entry (≤ 8 bytes) as a zero-extended
    /// little-endian word, without a length dispatch (PDO packing).
    #[inline(always)]
    pub fn word(&self, r: EntryRef) -> u64 {
        self.entry(r).value.word()
    }

    /// Overwrite a fixed-size value (≤ 8 bytes) from a word whose bits above
    /// the value's size are zero (PDO unpacking). Like [`set_le`] without a
    /// length dispatch; the caller owns the size invariant.
    ///
    /// [`set_le`]: ObjectDictionary::set_le
    #[inline(always)]
    pub fn set_word(&mut self, r: EntryRef, w: u64) {
        let s = &mut self.objects[r.obj as usize].subs[r.sub as usize];
        match s.value.set_word(w) {
            Some(changed) => {
                self.generation = self.generation.wrapping_add(u64::from(changed & s.marked));
            }
            None => {
                let n = s.value.len().min(8);
                self.set_le_slow(r, &w.to_le_bytes()[..n]);
            }
        }
    }

    /// Overwrite a fixed-size numeric value in place: no allocation, no
    /// change of length. Panics in debug builds if the size differs.
    #[inline(always)]
    pub fn set_le(&mut self, r: EntryRef, data: &[u8]) {
        let s = &mut self.objects[r.obj as usize].subs[r.sub as usize];
        match s.value.set_inline(data) {
            Some(changed) => {
                // Branch-free: counts only a change of a marked entry.
                self.generation = self.generation.wrapping_add(u64::from(changed & s.marked));
            }
            None => self.set_le_slow(r, data),
        }
    }

    /// `set_le` for values that are not 1/2/4/8 bytes inline.
    #[cold]
    #[inline(never)]
    fn set_le_slow(&mut self, r: EntryRef, data: &[u8]) {
        let s = &mut self.objects[r.obj as usize].subs[r.sub as usize];
        if !same_bytes(&s.value, data) {
            copy_small(s.value.as_mut_slice(), data);
            self.generation = self.generation.wrapping_add(u64::from(s.marked));
        }
    }

    /// Typed read of a numeric value at `(index, sub)` (no hook).
    pub fn get_value(&self, index: u16, sub: u8) -> Option<Value> {
        self.get(index, sub).map(SubObject::value)
    }
    /// Unsigned read (zero-extended) of a numeric value (no hook).
    pub fn get_u64(&self, index: u16, sub: u8) -> Option<u64> {
        self.get(index, sub).map(|s| crate::types::le_u64(&s.value))
    }
    /// Signed read (sign-extended) of a numeric value (no hook).
    pub fn get_i64(&self, index: u16, sub: u8) -> Option<i64> {
        self.get(index, sub).map(|s| crate::types::le_i64(&s.value))
    }
    /// Unsigned 32-bit read (no hook).
    pub fn get_u32(&self, index: u16, sub: u8) -> Option<u32> {
        self.get_u64(index, sub).map(|v| v as u32)
    }

    /// Set a value from the device side (no access check, no hook), checking
    /// type and encoding. Used by applications and services for their own objects.
    pub fn set_value(&mut self, index: u16, sub: u8, value: &Value) -> Result<(), SdoAbort> {
        let r = self.find(index, sub)?;
        let dt = self.entry(r).data_type;
        let bytes = value.encode(dt)?;
        self.set_raw(r, &bytes);
        Ok(())
    }

    /// SDO-style checked read: access, then the owner's refresh of a live
    /// entry, then the bytes.
    pub fn read<H: ObjectHooks + ?Sized>(
        &mut self,
        hooks: &mut H,
        index: u16,
        sub: u8,
    ) -> Result<&[u8], SdoAbort> {
        let r = self.find(index, sub)?;
        self.read_ref(hooks, r)?;
        Ok(self.bytes(r))
    }

    /// Checked read through a resolved handle: access, and the owner's
    /// refresh of a live entry. The bytes are then at
    /// [`ObjectDictionary::bytes`].
    #[inline]
    pub fn read_ref<H: ObjectHooks + ?Sized>(&mut self, hooks: &mut H, r: EntryRef) -> Result<(), SdoAbort> {
        let e = self.entry(r);
        if !e.access.readable() {
            return Err(SdoAbort::READ_WRITE_ONLY);
        }
        if e.live {
            let at = self.target(r);
            hooks.on_read(self, &at)?;
        }
        Ok(())
    }

    /// What a hook is told about an entry.
    #[inline]
    pub fn target(&self, r: EntryRef) -> Target {
        let o = &self.objects[r.obj as usize];
        let s = &o.subs[r.sub as usize];
        Target { r, index: o.index, sub: s.sub, owner: s.owner, watched: s.watched }
    }

    /// SDO-style checked write: the whole write path of [`crate::owner`]
    /// (find, access, type/length/limits, owner check, store, owner apply).
    pub fn write<H: ObjectHooks + ?Sized>(
        &mut self,
        hooks: &mut H,
        index: u16,
        sub: u8,
        data: &[u8],
    ) -> Result<(), SdoAbort> {
        let r = self.find(index, sub)?;
        self.write_ref(hooks, r, data)
    }

    /// Checked write through a resolved handle (steps 2–7).
    #[inline]
    pub fn write_ref<H: ObjectHooks + ?Sized>(
        &mut self,
        hooks: &mut H,
        r: EntryRef,
        data: &[u8],
    ) -> Result<(), SdoAbort> {
        if !self.entry(r).access.writable() {
            return Err(SdoAbort::WRITE_READ_ONLY);
        }
        self.write_local(hooks, r, data)
    }

    /// Write by the local device or a PDO: no access check, but type,
    /// length, limits and the owner apply (steps 3–7). RPDO writes use this
    /// after checking the mapping.
    #[inline]
    pub fn write_local<H: ObjectHooks + ?Sized>(
        &mut self,
        hooks: &mut H,
        r: EntryRef,
        data: &[u8],
    ) -> Result<(), SdoAbort> {
        let e = self.entry(r);
        e.validate(data)?;
        if e.owner == Owner::NONE && !e.watched {
            self.set_raw(r, data);
            return Ok(());
        }
        let at = self.target(r);
        match hooks.check_write(self, &at, data)? {
            WriteOutcome::Handled => self.bump_all(),
            WriteOutcome::Store => {
                self.set_raw(r, data);
                hooks.apply_write(self, &at);
            }
        }
        Ok(())
    }

    /// Reset every sub-object for which `pred(index, sub_object)` holds to
    /// its default value.
    pub fn restore_defaults(&mut self, mut pred: impl FnMut(u16, &SubObject) -> bool) {
        for o in &mut self.objects {
            for s in &mut o.subs {
                if pred(o.index, s) && *s.value != *s.default {
                    s.value.set(&s.default);
                }
            }
        }
        self.bump_all();
    }

    /// Every `(index, sub, bytes)` whose persistence group is `group` and whose
    /// value differs from the default or is writable: what 1010h stores.
    pub fn persistent_values(&self, group: PersistGroup) -> impl Iterator<Item = (u16, u8, &[u8])> + '_ {
        self.objects.iter().flat_map(move |o| {
            o.subs.iter().filter(move |s| s.persist == group).map(move |s| (o.index, s.sub, &*s.value))
        })
    }
}

#[cfg(test)]
#[path = "dict_tests.rs"]
mod tests;
