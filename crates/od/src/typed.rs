//! Typed hooks: application code that works with [`Value`]s rather than
//! little-endian bytes.

use crate::{ObjectDictionary, ObjectHooks, SdoAbort, Target, Value, WriteOutcome};

/// Hooks written against decoded values. Wrap in [`Typed`] to use them
/// wherever [`ObjectHooks`] are expected.
pub trait TypedHooks {
    /// The live value of a live entry, or `None` to keep the stored one.
    fn read(&mut self, index: u16, sub: u8) -> Result<Option<Value>, SdoAbort> {
        let _ = (index, sub);
        Ok(None)
    }
    /// Validate (and react to) a write of `value`; it is stored when this
    /// returns `Ok`.
    fn write(&mut self, index: u16, sub: u8, value: &Value) -> Result<(), SdoAbort> {
        let _ = (index, sub, value);
        Ok(())
    }
}

/// Adapter from [`TypedHooks`] to [`ObjectHooks`]: decodes writes with the
/// object's data type and encodes live values on reads.
#[derive(Debug, Default)]
pub struct Typed<T>(pub T);

impl<T: TypedHooks> ObjectHooks for Typed<T> {
    fn on_read(&mut self, od: &mut ObjectDictionary, at: &Target) -> Result<(), SdoAbort> {
        if let Some(v) = self.0.read(at.index, at.sub)? {
            let bytes = v.encode(od.entry(at.r).data_type)?;
            od.set_raw(at.r, &bytes);
        }
        Ok(())
    }

    fn check_write(
        &mut self,
        od: &mut ObjectDictionary,
        at: &Target,
        data: &[u8],
    ) -> Result<WriteOutcome, SdoAbort> {
        let value = Value::decode(od.entry(at.r).data_type, data)?;
        self.0.write(at.index, at.sub, &value)?;
        Ok(WriteOutcome::Store)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Access, DataType, Object, SubObject};

    struct Speed {
        actual: i32,
    }
    impl TypedHooks for Speed {
        fn read(&mut self, index: u16, _: u8) -> Result<Option<Value>, SdoAbort> {
            Ok((index == 0x606C).then_some(Value::I32(self.actual)))
        }
        fn write(&mut self, index: u16, _: u8, value: &Value) -> Result<(), SdoAbort> {
            match (index, value) {
                (0x60FF, Value::I32(v)) if v.unsigned_abs() > 10_000 => Err(SdoAbort::VALUE_TOO_HIGH),
                _ => Ok(()),
            }
        }
    }

    #[test]
    fn typed_values_in_and_out() {
        let mut od = ObjectDictionary::new();
        for (i, a) in [(0x606C, Access::Ro), (0x60FF, Access::Rww)] {
            od.insert(
                Object::with_code(i, crate::ObjectCode::Var, "x")
                    .with_sub(SubObject::new(0, "x", DataType::Integer32, a, Value::I32(0)).hooked()),
            );
        }
        let mut h = Typed(Speed { actual: -1234 });
        assert_eq!(od.read(&mut h, 0x606C, 0).unwrap(), (-1234i32).to_le_bytes());
        assert_eq!(od.write(&mut h, 0x60FF, 0, &20_000i32.to_le_bytes()), Err(SdoAbort::VALUE_TOO_HIGH));
        od.write(&mut h, 0x60FF, 0, &(-500i32).to_le_bytes()).unwrap();
        assert_eq!(od.get_i64(0x60FF, 0), Some(-500));
    }
}
