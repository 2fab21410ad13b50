//! [`PerFamily`]: one value per constraint family (weights, bounds,
//! toggles, diagnostics), indexed by [`Family`], and read and written in
//! presets as a table keyed by [`Family::name`].

use std::fmt;
use std::ops::{Index, IndexMut};

use serde::de::{self, MapAccess, Visitor};
use serde::ser::SerializeMap;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use super::Family;

/// One value per family, indexed by [`Family`].
///
/// In presets it is a table keyed by [`Family::name`]; a missing key keeps
/// its default, an unknown key is an error naming the families. `None`
/// entries are left out when written.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct PerFamily<T>([T; Family::COUNT]);

impl<T> PerFamily<T> {
    /// A value for each family from `f`.
    pub fn from_fn(f: impl FnMut(Family) -> T) -> Self {
        Self(Family::ALL.map(f))
    }

    /// The same value for every family.
    pub fn splat(value: T) -> Self
    where
        T: Clone,
    {
        Self::from_fn(|_| value.clone())
    }

    /// Every family with its value, in [`Family::ALL`] order.
    pub fn iter(&self) -> impl Iterator<Item = (Family, &T)> {
        Family::ALL.into_iter().map(|f| (f, &self[f]))
    }

    /// Every family's value, mutably, in [`Family::ALL`] order.
    pub fn iter_mut(&mut self) -> impl Iterator<Item = &mut T> {
        self.0.iter_mut()
    }

    /// A value for each family from this one's.
    pub fn map<U>(&self, mut f: impl FnMut(Family, &T) -> U) -> PerFamily<U> {
        PerFamily::from_fn(|fam| f(fam, &self[fam]))
    }

    /// This, with `family`'s value replaced.
    pub fn with(mut self, family: Family, value: T) -> Self {
        self[family] = value;
        self
    }

    /// Reads a preset table over `base`: the keys given replace their
    /// family's value, the others keep `base`'s.
    pub fn deserialize_over<'de, D>(base: Self, d: D) -> Result<Self, D::Error>
    where
        D: Deserializer<'de>,
        T: Deserialize<'de>,
    {
        struct Over<T>(PerFamily<T>);
        impl<'de, T: Deserialize<'de>> Visitor<'de> for Over<T> {
            type Value = PerFamily<T>;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                write!(f, "a table with keys among {}", Family::NAMES.join(", "))
            }
            fn visit_map<A: MapAccess<'de>>(mut self, mut map: A) -> Result<Self::Value, A::Error> {
                while let Some(Key(family)) = map.next_key()? {
                    self.0[family] = map.next_value()?;
                }
                Ok(self.0)
            }
        }
        d.deserialize_map(Over(base))
    }
}

/// A family's name as a table key: an unknown one is refused while the key
/// is read (as a struct's unknown field is), so the error's path ends in it.
struct Key(Family);

impl<'de> Deserialize<'de> for Key {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Name;
        impl Visitor<'_> for Name {
            type Value = Key;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                write!(f, "one of {}", Family::NAMES.join(", "))
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Key, E> {
                Family::from_name(v)
                    .map(Key)
                    .ok_or_else(|| E::unknown_field(v, &Family::NAMES))
            }
        }
        d.deserialize_identifier(Name)
    }
}

impl PerFamily<f32> {
    /// Every family's default weight ([`Family::default_weight`]).
    pub fn default_weights() -> Self {
        Self::from_fn(Family::default_weight)
    }
}

impl<T: Default> Default for PerFamily<T> {
    fn default() -> Self {
        Self::from_fn(|_| T::default())
    }
}

impl<T> IntoIterator for PerFamily<T> {
    type Item = T;
    type IntoIter = std::array::IntoIter<T, { Family::COUNT }>;

    /// The values in [`Family::ALL`] order.
    fn into_iter(self) -> Self::IntoIter {
        self.0.into_iter()
    }
}

impl<T> Index<Family> for PerFamily<T> {
    type Output = T;
    fn index(&self, f: Family) -> &T {
        &self.0[f.index()]
    }
}

impl<T> IndexMut<Family> for PerFamily<T> {
    fn index_mut(&mut self, f: Family) -> &mut T {
        &mut self.0[f.index()]
    }
}

/// A value a [`PerFamily`] table can hold in a preset; `present` is false
/// for values left out when written (`None`).
pub trait Entry: Serialize {
    /// Whether the value is written.
    fn present(&self) -> bool {
        true
    }
}

impl Entry for f32 {}
impl Entry for bool {}
impl<T: Serialize> Entry for Option<T> {
    fn present(&self) -> bool {
        self.is_some()
    }
}

impl<T: Entry> Serialize for PerFamily<T> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(None)?;
        for (name, v) in Family::NAMES.iter().zip(&self.0) {
            if v.present() {
                map.serialize_entry(name, v)?;
            }
        }
        map.end()
    }
}

impl<'de, T: Deserialize<'de> + Default> Deserialize<'de> for PerFamily<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Self::deserialize_over(Self::default(), d)
    }
}
