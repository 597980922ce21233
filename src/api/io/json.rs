//! JSON parsing that refuses duplicate object keys. serde_json keeps the last of two equal
//! keys silently, so a graph with the same node id twice would run only the second; here the
//! second is an error naming the key, with serde_json's line and column.

use serde::de::{self, DeserializeSeed, MapAccess, SeqAccess, Visitor};
use serde_json::{Map, Value};
use std::fmt;

/// Parses `text` as JSON, failing on an object with the same key twice (at any depth).
pub fn parse_strict(text: &str) -> Result<Value, serde_json::Error> {
    let mut de = serde_json::Deserializer::from_str(text);
    let v = StrictValue.deserialize(&mut de)?;
    de.end()?;
    Ok(v)
}

/// A seed that builds a `serde_json::Value`, checking every object for repeated keys.
struct StrictValue;

impl<'de> DeserializeSeed<'de> for StrictValue {
    type Value = Value;
    fn deserialize<D: de::Deserializer<'de>>(self, d: D) -> Result<Value, D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> Visitor<'de> for StrictValue {
    type Value = Value;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("any JSON value")
    }
    fn visit_bool<E>(self, v: bool) -> Result<Value, E> {
        Ok(Value::Bool(v))
    }
    fn visit_i64<E>(self, v: i64) -> Result<Value, E> {
        Ok(Value::from(v))
    }
    fn visit_u64<E>(self, v: u64) -> Result<Value, E> {
        Ok(Value::from(v))
    }
    fn visit_f64<E>(self, v: f64) -> Result<Value, E> {
        Ok(serde_json::Number::from_f64(v).map_or(Value::Null, Value::Number))
    }
    fn visit_str<E>(self, v: &str) -> Result<Value, E> {
        Ok(Value::String(v.to_string()))
    }
    fn visit_string<E>(self, v: String) -> Result<Value, E> {
        Ok(Value::String(v))
    }
    fn visit_unit<E>(self) -> Result<Value, E> {
        Ok(Value::Null)
    }
    fn visit_none<E>(self) -> Result<Value, E> {
        Ok(Value::Null)
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Value, A::Error> {
        let mut v = Vec::new();
        while let Some(x) = seq.next_element_seed(StrictValue)? {
            v.push(x);
        }
        Ok(Value::Array(v))
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Value, A::Error> {
        let mut m = Map::new();
        while let Some(k) = map.next_key::<String>()? {
            if m.contains_key(&k) {
                return Err(de::Error::custom(format!("duplicate key '{k}'")));
            }
            let v = map.next_value_seed(StrictValue)?;
            m.insert(k, v);
        }
        Ok(Value::Object(m))
    }
}

#[cfg(test)]
mod tests {
    use super::parse_strict;

    #[test]
    fn a_repeated_key_is_an_error_with_its_line() {
        let e = parse_strict("{\"nodes\": {\n \"a\": {},\n \"a\": {\"x\": 1}\n}}").unwrap_err();
        assert!(e.to_string().contains("duplicate key 'a'"), "{e}");
        assert_eq!(e.line(), 3);
        let e = parse_strict(r#"{"p": {"k": 1, "k": 2}}"#).unwrap_err();
        assert!(e.to_string().contains("duplicate key 'k'"), "{e}");
    }

    #[test]
    fn equal_keys_in_different_objects_are_fine() {
        let v = parse_strict(r#"{"a": {"k": 1}, "b": {"k": [1, 2.5, "s", null, true]}}"#).unwrap();
        assert_eq!(v["b"]["k"][1], serde_json::json!(2.5));
        assert_eq!(
            v,
            serde_json::from_str::<serde_json::Value>(&v.to_string()).unwrap()
        );
    }
}
