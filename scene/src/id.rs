//! [`SceneId`]: the typed name of a scene (a scene file's `name`), the key by which the
//! compiled-scene registries (bf-generated's `SCENES`/`SCENE_KERNELS`, bf-model's registry)
//! and the problem catalogue look scenes up. It is a name, not a closed list: a scene file
//! dropped into `scenes/` is compiled in under its own name with no edit here. Text from a
//! user becomes an id only against the list of scenes that exist ([`SceneId::parse_among`]),
//! so an unknown name is reported with the known ones.

use std::borrow::Cow;
use std::fmt;

use crate::Scene;

/// The name of a scene (its file's `name`, a Rust identifier).
#[derive(Debug, Clone, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct SceneId(Cow<'static, str>);

impl SceneId {
    /// `scenes/paper.toml`: the paper's robotic finger (Sect. 2, 6).
    pub const PAPER: SceneId = SceneId::from_static("paper");
    /// `scenes/human.toml`: the human-finger variant (Sect. 6).
    pub const HUMAN: SceneId = SceneId::from_static("human");

    /// The id of a scene whose name is known at compile time (a registry entry's name).
    pub const fn from_static(name: &'static str) -> SceneId {
        SceneId(Cow::Borrowed(name))
    }

    /// The name.
    pub fn as_str(&self) -> &str {
        &self.0
    }

    /// The id among `known` spelled `text`; the error names `text` and lists `known`.
    pub fn parse_among<'a>(
        text: &str,
        known: impl IntoIterator<Item = &'a SceneId>,
    ) -> Result<SceneId, UnknownScene> {
        let known: Vec<&SceneId> = known.into_iter().collect();
        known
            .iter()
            .find(|id| id.as_str() == text)
            .map(|id| (*id).clone())
            .ok_or_else(|| UnknownScene {
                name: text.to_string(),
                known: known.iter().map(|id| id.as_str().to_string()).collect(),
            })
    }
}

impl fmt::Display for SceneId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl AsRef<str> for SceneId {
    fn as_ref(&self) -> &str {
        &self.0
    }
}

impl Scene {
    /// The scene's id (its `name`).
    pub fn id(&self) -> SceneId {
        SceneId(Cow::Owned(self.name.clone()))
    }
}

/// A scene name that is none of the known scenes ([`SceneId::parse_among`]).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown scene `{name}`; available: {}", known.join(", "))]
pub struct UnknownScene {
    /// The name asked for.
    pub name: String,
    /// The known scenes, in the order given.
    pub known: Vec<String>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parsing_finds_a_known_scene_and_lists_them_otherwise() {
        let known = [SceneId::HUMAN, SceneId::PAPER];
        assert_eq!(SceneId::parse_among("paper", &known), Ok(SceneId::PAPER));
        let e = SceneId::parse_among("Paper", &known).unwrap_err();
        assert_eq!(
            e.to_string(),
            "unknown scene `Paper`; available: human, paper"
        );
        let e = SceneId::parse_among("x", []).unwrap_err();
        assert!(e.known.is_empty(), "{e}");
    }

    #[test]
    fn an_owned_and_a_static_id_of_one_name_are_equal() {
        let owned = SceneId(Cow::Owned("paper".to_string()));
        assert_eq!(owned, SceneId::PAPER);
        assert_eq!(owned.cmp(&SceneId::HUMAN), "paper".cmp("human"));
        assert_eq!(format!("{owned}"), "paper");
    }
}
