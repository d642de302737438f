//! Key help: every key a plugin reacts to is registered with [`RegisterKeys::register_keys`],
//! so that the help overlay and the key reference (`docs/reference.md`) list exactly the keys that
//! work.

use super::kind::EntityKind;
use bevy::prelude::*;

/// Where a key works: everywhere, or in scenes holding an entity of one kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum KeyScope {
    /// In every scene.
    Global,
    /// In scenes with an entity of this kind.
    Kind(&'static str),
}

/// One key and what it does, for the help overlay.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct KeyHelp {
    /// The key.
    pub key: KeyCode,
    /// What it does, as a short phrase.
    pub action: &'static str,
    /// Where it works.
    pub scope: KeyScope,
}

impl KeyHelp {
    /// The key's name as printed on a keyboard: `J` for `KeyJ`, `5` for `Digit5`,
    /// `ArrowLeft` as is.
    pub fn key_name(&self) -> String {
        let name = format!("{:?}", self.key);
        name.strip_prefix("Key").or_else(|| name.strip_prefix("Digit")).unwrap_or(&name).to_string()
    }
}

/// Every registered key, in registration order.
#[derive(Resource, Debug, Default)]
pub struct KeyMap(pub Vec<KeyHelp>);

impl KeyMap {
    /// The keys that work in a scene holding entities of `kinds`.
    pub fn active<'a>(&'a self, kinds: &'a [&str]) -> impl Iterator<Item = &'a KeyHelp> + 'a {
        self.0.iter().filter(move |help| match help.scope {
            KeyScope::Global => true,
            KeyScope::Kind(kind) => kinds.contains(&kind),
        })
    }
}

/// Registration of keys on the app.
pub trait RegisterKeys {
    /// Adds keys to the [`KeyMap`].
    fn register_keys(&mut self, keys: &[KeyHelp]) -> &mut Self;

    /// Adds keys, each `(key, action)`, that work in scenes with an entity of kind `K`.
    fn register_kind_keys<K: EntityKind>(&mut self, keys: &[(KeyCode, &'static str)]) -> &mut Self {
        let scope = KeyScope::Kind(K::KEY);
        self.register_keys(&keys.iter().map(|&(key, action)| KeyHelp { key, action, scope }).collect::<Vec<_>>())
    }
}

impl RegisterKeys for App {
    fn register_keys(&mut self, keys: &[KeyHelp]) -> &mut Self {
        self.world_mut().get_resource_or_init::<KeyMap>().0.extend_from_slice(keys);
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn key_names_read_like_the_keyboard() {
        let help = |key| KeyHelp { key, action: "", scope: KeyScope::Global };
        assert_eq!(help(KeyCode::KeyJ).key_name(), "J");
        assert_eq!(help(KeyCode::Digit5).key_name(), "5");
        assert_eq!(help(KeyCode::ArrowLeft).key_name(), "ArrowLeft");
    }

    #[test]
    fn kind_keys_show_only_where_the_kind_is() {
        let map = KeyMap(vec![
            KeyHelp { key: KeyCode::Space, action: "a", scope: KeyScope::Global },
            KeyHelp { key: KeyCode::KeyW, action: "b", scope: KeyScope::Kind("sloth") },
        ]);
        assert_eq!(map.active(&["shape"]).count(), 1);
        assert_eq!(map.active(&["sloth"]).count(), 2);
    }
}
