//! Fixed-length arrays read strictly. serde reads `[f64; 3]` from a TOML array by taking the
//! first three elements and ignoring the rest, so `size = [10, 10, 10, "oops"]` would load as
//! `[10, 10, 10]`: a silently dropped input. Every fixed-length array in `format.rs` goes
//! through these functions instead, which refuse too few and too many elements alike.
//!
//! The two fields that take one of two shapes (`walls`, `scale`) are read here by hand too:
//! serde's untagged enums answer any mistake with "data did not match any variant of untagged
//! enum", which names neither what is wrong nor what is allowed.

use std::fmt;
use std::marker::PhantomData;

use serde::de::value::{MapAccessDeserializer, SeqAccessDeserializer};
use serde::de::{self, Deserialize, Deserializer, IgnoredAny, MapAccess, SeqAccess, Visitor};

use super::format::{EachWall, ScaleSpec, WallsSpec};

/// An array of exactly `N` elements (`#[serde(deserialize_with = "fixed::exact")]`).
pub fn exact<'de, D, T, const N: usize>(d: D) -> Result<[T; N], D::Error>
where
    D: Deserializer<'de>,
    T: Deserialize<'de>,
{
    d.deserialize_seq(Exact::<T, N>(PhantomData))
}

/// An optional array of exactly `N` elements (with `#[serde(default)]`).
pub fn exact_opt<'de, D, T, const N: usize>(d: D) -> Result<Option<[T; N]>, D::Error>
where
    D: Deserializer<'de>,
    T: Deserialize<'de>,
{
    exact(d).map(Some)
}

/// An optional list of arrays of exactly `N` elements each (with `#[serde(default)]`).
pub fn exact_list<'de, D, T, const N: usize>(d: D) -> Result<Option<Vec<[T; N]>>, D::Error>
where
    D: Deserializer<'de>,
    T: Deserialize<'de>,
{
    Vec::<Strict<T, N>>::deserialize(d).map(|v| Some(v.into_iter().map(|s| s.0).collect()))
}

/// One strictly read array, for lists of them.
struct Strict<T, const N: usize>([T; N]);

impl<'de, T: Deserialize<'de>, const N: usize> Deserialize<'de> for Strict<T, N> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        exact(d).map(Strict)
    }
}

struct Exact<T, const N: usize>(PhantomData<T>);

impl<'de, T: Deserialize<'de>, const N: usize> Visitor<'de> for Exact<T, N> {
    type Value = [T; N];

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "an array of exactly {N} elements")
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<[T; N], A::Error> {
        let mut out = Vec::with_capacity(N);
        while out.len() < N {
            match seq.next_element()? {
                Some(v) => out.push(v),
                None => return Err(de::Error::invalid_length(out.len(), &self)),
            }
        }
        // Count what is left (of any type) so the message can say how many there were.
        let mut len = N;
        while seq.next_element::<IgnoredAny>()?.is_some() {
            len += 1;
        }
        if len > N {
            return Err(de::Error::invalid_length(len, &self));
        }
        out.try_into()
            .map_err(|_| de::Error::invalid_length(N, &self))
    }
}

impl<'de> Deserialize<'de> for WallsSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Walls;
        impl<'de> Visitor<'de> for Walls {
            type Value = WallsSpec;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(
                    "a material name for all six walls, or a table { px, nx, py, ny, pz, nz } naming one per wall",
                )
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<WallsSpec, E> {
                Ok(WallsSpec::All(v.to_string()))
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<WallsSpec, A::Error> {
                EachWall::deserialize(MapAccessDeserializer::new(map)).map(WallsSpec::Each)
            }
        }
        d.deserialize_any(Walls)
    }
}

impl<'de> Deserialize<'de> for ScaleSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Scale;
        impl<'de> Visitor<'de> for Scale {
            type Value = ScaleSpec;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a number (uniform scale) or an array of exactly 3 numbers [x, y, z]")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<ScaleSpec, E> {
                Ok(ScaleSpec::Uniform(v))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<ScaleSpec, E> {
                Ok(ScaleSpec::Uniform(v as f64))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<ScaleSpec, E> {
                Ok(ScaleSpec::Uniform(v as f64))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<ScaleSpec, A::Error> {
                exact(SeqAccessDeserializer::new(seq)).map(ScaleSpec::PerAxis)
            }
        }
        d.deserialize_any(Scale)
    }
}
