//! The kinds of a registry as a list of types, through which serde reads and writes each
//! entity's definition as its kind's own type.

use crate::foundation::kind::{EntityKind, KindDef};
use serde::de::MapAccess;
use serde::ser::SerializeMap;
use std::marker::PhantomData;

/// A kind's key and its definition, as an entity's mapping holds them.
pub type KindValue = (&'static str, Box<dyn KindDef>);

/// The kinds of `L`, then kind `K`: a node of a [`KindList`].
pub struct Then<L, K>(PhantomData<fn() -> (L, K)>);

/// A list of kinds known by type, so that serde can read and write each kind's definition
/// with the deserializer at hand (and its errors keep their place in the file).
pub trait KindList: Send + Sync + 'static {
    /// Every key, in registration order.
    fn keys() -> Vec<&'static str>;

    /// Reads the value of an entity's `key` as that kind's definition; `None` if no kind has
    /// the key.
    fn next_value<'de, A: MapAccess<'de>>(key: &str, map: &mut A) -> Option<Result<KindValue, A::Error>>;

    /// Writes `def` as the value of `key`; `None` if no kind has the key.
    fn serialize_entry<M: SerializeMap>(key: &str, def: &dyn KindDef, map: &mut M) -> Option<Result<(), M::Error>>;
}

impl KindList for () {
    fn keys() -> Vec<&'static str> {
        Vec::new()
    }

    fn next_value<'de, A: MapAccess<'de>>(_key: &str, _map: &mut A) -> Option<Result<KindValue, A::Error>> {
        None
    }

    fn serialize_entry<M: SerializeMap>(_key: &str, _def: &dyn KindDef, _map: &mut M) -> Option<Result<(), M::Error>> {
        None
    }
}

impl<L: KindList, K: EntityKind> KindList for Then<L, K> {
    fn keys() -> Vec<&'static str> {
        let mut keys = L::keys();
        keys.push(K::KEY);
        keys
    }

    fn next_value<'de, A: MapAccess<'de>>(key: &str, map: &mut A) -> Option<Result<KindValue, A::Error>> {
        if key != K::KEY {
            return L::next_value(key, map);
        }
        Some(map.next_value::<K::Def>().map(|def| (K::KEY, Box::new(def) as Box<dyn KindDef>)))
    }

    fn serialize_entry<M: SerializeMap>(key: &str, def: &dyn KindDef, map: &mut M) -> Option<Result<(), M::Error>> {
        if key != K::KEY {
            return L::serialize_entry(key, def, map);
        }
        let def = def.as_any().downcast_ref::<K::Def>()?;
        Some(map.serialize_entry(key, def))
    }
}
