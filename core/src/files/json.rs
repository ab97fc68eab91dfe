//! JSON read from a user's file, every object's keys once. serde_json keeps the last of two
//! equal keys without a word (`{"time": 0, "time": 5}` is a time of 5), and so does every
//! type read through a map; a hand-edited trajectory or baseline with a key written twice is a
//! slip the user should hear of, with the line it is on.

use serde::de::{self, Deserializer, MapAccess, SeqAccess, Visitor};
use serde_json::Value;

/// `text` as a JSON value, refused (with serde_json's line and column) where an object names
/// a key twice: [`check_unique_keys`], then serde_json's own parse (user files here are small;
/// two passes keep one walker of the keys).
pub fn parse_unique_keys(text: &str) -> Result<Value, serde_json::Error> {
    check_unique_keys(text)?;
    serde_json::from_str(text)
}

/// Refuses `text` (with serde_json's line and column) where an object names a key twice,
/// building nothing: a typed parse (or [`parse_unique_keys`]) reads the document after it,
/// and a glTF file's embedded buffers are never held twice.
pub fn check_unique_keys(text: &str) -> Result<(), serde_json::Error> {
    let mut de = serde_json::Deserializer::from_str(text);
    de.deserialize_any(KeysOnly)?;
    de.end()
}

/// Walks a JSON value, keeping only each object's keys while it is read.
#[derive(Clone, Copy)]
struct KeysOnly;

impl<'de> Visitor<'de> for KeysOnly {
    type Value = ();

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("any JSON value")
    }

    fn visit_bool<E>(self, _: bool) -> Result<(), E> {
        Ok(())
    }

    fn visit_i64<E>(self, _: i64) -> Result<(), E> {
        Ok(())
    }

    fn visit_u64<E>(self, _: u64) -> Result<(), E> {
        Ok(())
    }

    fn visit_f64<E>(self, _: f64) -> Result<(), E> {
        Ok(())
    }

    fn visit_str<E>(self, _: &str) -> Result<(), E> {
        Ok(())
    }

    fn visit_unit<E>(self) -> Result<(), E> {
        Ok(())
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
        while seq.next_element_seed(self)?.is_some() {}
        Ok(())
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<(), A::Error> {
        let mut keys = std::collections::HashSet::new();
        while let Some(key) = map.next_key::<String>()? {
            if keys.contains(&key) {
                return Err(de::Error::custom(format!(
                    "the key `{key}` is written twice in one object (JSON keeps one of them \
                     silently; write it once)"
                )));
            }
            keys.insert(key);
            map.next_value_seed(self)?;
        }
        Ok(())
    }
}

impl<'de> de::DeserializeSeed<'de> for KeysOnly {
    type Value = ();

    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        d.deserialize_any(self)
    }
}

#[cfg(test)]
mod tests {
    use super::{check_unique_keys, parse_unique_keys};

    /// A key twice, at any depth, is refused with its line; the same text without it reads as
    /// serde_json reads it.
    #[test]
    fn a_key_written_twice_is_refused_with_its_line() {
        let twice = "[\n  {\"time\": 0,\n   \"time\": 5}\n]";
        let e = parse_unique_keys(twice).unwrap_err();
        assert!(e.to_string().contains("`time` is written twice"), "{e}");
        assert_eq!(e.line(), 3, "{e}");
        let nested = r#"{"a": {"b": [1, {"c": 1, "c": 2}]}}"#;
        assert!(parse_unique_keys(nested).is_err());
        let once = r#"{"a": {"b": [1, 2.5, -3, true, null, "x", {"c": 1}]}, "d": {}}"#;
        let plain: serde_json::Value = serde_json::from_str(once).unwrap();
        assert_eq!(parse_unique_keys(once).unwrap(), plain);
        assert!(parse_unique_keys("{} x").is_err(), "trailing text");
        // The check alone says the same, line included, and passes what the parse passes.
        let e = check_unique_keys(twice).unwrap_err();
        assert!(
            e.to_string().contains("`time` is written twice") && e.line() == 3,
            "{e}"
        );
        assert!(check_unique_keys(nested).is_err());
        assert!(check_unique_keys(once).is_ok());
        assert!(check_unique_keys("{} x").is_err(), "trailing text");
    }
}
