//! Fixed-length arrays read strictly. serde reads `[f64; 3]` from a TOML array by taking the
//! first three elements and ignoring the rest, so `size = [10, 10, 10, "oops"]` would load as
//! `[10, 10, 10]`: a silently dropped input. Every fixed-length array in `format.rs` goes
//! through these functions instead, which refuse too few and too many elements alike.
//! It knows nothing of the scene format (`format.rs` uses it, not the other way round).

use std::fmt;
use std::marker::PhantomData;

use serde::de::{self, Deserialize, Deserializer, IgnoredAny, SeqAccess, Visitor};

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
