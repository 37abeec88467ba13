//! Finds the first non-finite number in any serialisable value, by its key path. serde_json
//! would silently write NaN and infinity as `null`; a report must instead refuse them (a
//! non-finite value is a failed computation), and this check says where it is.

use serde::ser::{self, Serialize};

/// The path (e.g. `lyapunov.along_cycle.re_slow[12]`) of the first NaN or infinity in
/// `value`, or None if every number is finite. `root` names the value.
pub fn first_non_finite<T: Serialize + ?Sized>(value: &T, root: &str) -> Option<String> {
    let mut walker = Walker { path: vec![root.to_string()], found: None };
    // The walker never fails; it only records.
    let _ = value.serialize(&mut walker);
    walker.found
}

struct Walker {
    path: Vec<String>,
    found: Option<String>,
}

#[derive(Debug)]
struct Never;

impl std::fmt::Display for Never {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("unreachable")
    }
}

impl std::error::Error for Never {}

impl ser::Error for Never {
    fn custom<M: std::fmt::Display>(_: M) -> Self {
        Never
    }
}

impl Walker {
    fn number(&mut self, x: f64) {
        if !x.is_finite() && self.found.is_none() {
            self.found = Some(self.path.concat());
        }
    }

    fn child<T: Serialize + ?Sized>(&mut self, segment: String, value: &T) {
        if self.found.is_some() {
            return;
        }
        self.path.push(segment);
        let _ = value.serialize(&mut *self);
        self.path.pop();
    }
}

/// Compound values: sequences count their elements, maps and structs name them.
struct Compound<'a> {
    walker: &'a mut Walker,
    index: usize,
    key: Option<String>,
}

/// Serializer methods for values that hold no number: each does nothing.
macro_rules! ignored {
    ($($method:ident($($arg:ty),*)),*) => {$(
        fn $method(self, $(_: $arg),*) -> Result<(), Never> {
            Ok(())
        }
    )*};
}

/// Serializer methods that open a compound value: each starts a fresh [`Compound`].
macro_rules! compound {
    ($($method:ident($($arg:ty),*)),*) => {$(
        fn $method(self, $(_: $arg),*) -> Result<Compound<'a>, Never> {
            Ok(Compound { walker: self, index: 0, key: None })
        }
    )*};
}

impl<'a> ser::Serializer for &'a mut Walker {
    type Ok = ();
    type Error = Never;
    type SerializeSeq = Compound<'a>;
    type SerializeTuple = Compound<'a>;
    type SerializeTupleStruct = Compound<'a>;
    type SerializeTupleVariant = Compound<'a>;
    type SerializeMap = Compound<'a>;
    type SerializeStruct = Compound<'a>;
    type SerializeStructVariant = Compound<'a>;

    ignored!(
        serialize_bool(bool),
        serialize_i8(i8),
        serialize_i16(i16),
        serialize_i32(i32),
        serialize_i64(i64),
        serialize_u8(u8),
        serialize_u16(u16),
        serialize_u32(u32),
        serialize_u64(u64),
        serialize_char(char),
        serialize_str(&str),
        serialize_bytes(&[u8]),
        serialize_none(),
        serialize_unit(),
        serialize_unit_struct(&'static str),
        serialize_unit_variant(&'static str, u32, &'static str)
    );
    fn serialize_f32(self, v: f32) -> Result<(), Never> {
        self.number(v as f64);
        Ok(())
    }
    fn serialize_f64(self, v: f64) -> Result<(), Never> {
        self.number(v);
        Ok(())
    }
    fn serialize_some<T: Serialize + ?Sized>(self, value: &T) -> Result<(), Never> {
        value.serialize(self)
    }
    fn serialize_newtype_struct<T: Serialize + ?Sized>(
        self,
        _: &'static str,
        value: &T,
    ) -> Result<(), Never> {
        value.serialize(self)
    }
    fn serialize_newtype_variant<T: Serialize + ?Sized>(
        self,
        _: &'static str,
        _: u32,
        variant: &'static str,
        value: &T,
    ) -> Result<(), Never> {
        self.child(format!(".{variant}"), value);
        Ok(())
    }
    compound!(
        serialize_seq(Option<usize>),
        serialize_tuple(usize),
        serialize_tuple_struct(&'static str, usize),
        serialize_tuple_variant(&'static str, u32, &'static str, usize),
        serialize_map(Option<usize>),
        serialize_struct(&'static str, usize),
        serialize_struct_variant(&'static str, u32, &'static str, usize)
    );
}

impl Compound<'_> {
    fn element<T: Serialize + ?Sized>(&mut self, value: &T) {
        let segment = format!("[{}]", self.index);
        self.index += 1;
        self.walker.child(segment, value);
    }
}

macro_rules! sequence_like {
    ($($trait:ident :: $method:ident),*) => {$(
        impl ser::$trait for Compound<'_> {
            type Ok = ();
            type Error = Never;
            fn $method<T: Serialize + ?Sized>(&mut self, value: &T) -> Result<(), Never> {
                self.element(value);
                Ok(())
            }
            fn end(self) -> Result<(), Never> {
                Ok(())
            }
        }
    )*};
}

sequence_like!(
    SerializeSeq::serialize_element,
    SerializeTuple::serialize_element,
    SerializeTupleStruct::serialize_field,
    SerializeTupleVariant::serialize_field
);

impl ser::SerializeMap for Compound<'_> {
    type Ok = ();
    type Error = Never;
    fn serialize_key<T: Serialize + ?Sized>(&mut self, key: &T) -> Result<(), Never> {
        self.key = serde_json::to_value(key).ok().map(|k| match k {
            serde_json::Value::String(s) => s,
            other => other.to_string(),
        });
        Ok(())
    }
    fn serialize_value<T: Serialize + ?Sized>(&mut self, value: &T) -> Result<(), Never> {
        let key = self.key.take().unwrap_or_else(|| "?".into());
        self.walker.child(format!(".{key}"), value);
        Ok(())
    }
    fn end(self) -> Result<(), Never> {
        Ok(())
    }
}

macro_rules! struct_like {
    ($($trait:ident),*) => {$(
        impl ser::$trait for Compound<'_> {
            type Ok = ();
            type Error = Never;
            fn serialize_field<T: Serialize + ?Sized>(&mut self, key: &'static str, value: &T) -> Result<(), Never> {
                self.walker.child(format!(".{key}"), value);
                Ok(())
            }
            fn end(self) -> Result<(), Never> {
                Ok(())
            }
        }
    )*};
}

struct_like!(SerializeStruct, SerializeStructVariant);

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(serde::Serialize)]
    struct Inner {
        values: Vec<f64>,
        pair: Option<[f64; 2]>,
    }

    #[derive(serde::Serialize)]
    struct Outer {
        name: String,
        inner: Inner,
        #[serde(flatten)]
        extra: Option<Inner>,
    }

    #[test]
    fn names_the_first_non_finite_number() {
        let ok = Outer {
            name: "a".into(),
            inner: Inner { values: vec![1.0, 2.0], pair: Some([0.0, 1.0]) },
            extra: None,
        };
        assert_eq!(first_non_finite(&ok, "x"), None);
        let bad = Outer {
            name: "a".into(),
            inner: Inner { values: vec![1.0, f64::NAN], pair: None },
            extra: None,
        };
        assert_eq!(first_non_finite(&bad, "x").as_deref(), Some("x.inner.values[1]"));
        let flat = Outer {
            name: "a".into(),
            inner: Inner { values: vec![], pair: None },
            extra: Some(Inner { values: vec![], pair: Some([0.0, f64::INFINITY]) }),
        };
        assert_eq!(first_non_finite(&flat, "x").as_deref(), Some("x.pair[1]"));
    }
}
