//! The events metadata JSON of PX4's libevents (version 1 and 2): components by id, each
//! with a namespace, enums and groups of events by sub-id. JSON objects are read in
//! document order, as the Python parser iterates them.

use std::collections::HashMap;
use std::fmt;
use std::marker::PhantomData;
use std::sync::Arc;

use serde::Deserialize;

use crate::pytext::python_int;
use serde::de::{self, MapAccess, Visitor};

/// An event's definition.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EventDef {
    /// Its name (`commander_armed_by`).
    pub name: String,
    /// Its message template (`Armed by {1}`).
    pub message: String,
    /// Its description template, if it has one.
    pub description: Option<String>,
    /// Its arguments, in order.
    pub arguments: Vec<ArgDef>,
    /// Its type (`summary`, `append_health_and_arming_messages`), if it has one.
    pub kind: Option<String>,
}

/// An argument of an event.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ArgDef {
    /// Its name.
    pub name: String,
    /// Its type: a basic type (`uint8_t` ... `int64_t`, `float`) or an enum, qualified
    /// (`px4::navigation_mode_t`) or of the event's namespace.
    pub ty: String,
    /// Its description, if it has one.
    pub description: Option<String>,
}

/// An enum of the metadata.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EnumDef {
    /// The basic type of its values.
    pub base: String,
    /// Whether values are bit sets, shown as the descriptions of their bits.
    pub is_bitfield: bool,
    /// Between the bits of a bitfield (`|` unless the metadata says otherwise).
    pub separator: String,
    /// Entries in the metadata's order: value (`None` if the key is not an integer),
    /// name, description.
    pub entries: Vec<(Option<i128>, String, Option<String>)>,
}

/// One component: its namespace, and its groups of events in the metadata's order.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Component {
    /// The component id (the top 8 bits of its events' ids).
    pub id: i128,
    /// Its namespace (`px4`, `common`).
    pub namespace: String,
    /// Groups (`default`, `arming_check`, `health`...) with their events by sub-id.
    pub groups: Vec<(String, HashMap<u32, EventDef>)>,
}

/// Everything an events metadata JSON defines.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct EventDefinitions {
    /// Its format version.
    pub version: i64,
    /// Components, in the metadata's order.
    pub components: Vec<Component>,
    /// Enums by qualified name (`px4::arm_disarm_reason_t`).
    pub enums: HashMap<String, Arc<EnumDef>>,
}

/// Where an event was found.
#[derive(Debug, Clone, Copy)]
pub struct Found<'a> {
    /// Its component.
    pub component: &'a Component,
    /// Its group's name.
    pub group: &'a str,
    /// Its definition.
    pub event: &'a EventDef,
}

impl EventDefinitions {
    /// Reads a metadata JSON document.
    pub fn from_json(json: &[u8]) -> Result<EventDefinitions, DefinitionsError> {
        let raw: RawDefinitions = serde_json::from_slice(json).map_err(DefinitionsError::Json)?;
        let version = raw.version.unwrap_or(0.0);
        if version < 1.0 {
            return Err(DefinitionsError::Version(version));
        }
        let mut out = EventDefinitions {
            version: version as i64,
            ..EventDefinitions::default()
        };
        for (key, comp) in raw.components.0 {
            let id = python_int(&key).ok_or(DefinitionsError::Key(key.clone()))?;
            let mut groups = Vec::new();
            for (name, group) in comp.event_groups.0 {
                let mut events = HashMap::new();
                for (sub, ev) in group.events.map(|e| e.0).unwrap_or_default() {
                    let sub_id = python_int(&sub).ok_or(DefinitionsError::Key(sub.clone()))?;
                    let Ok(sub_id) = u32::try_from(sub_id) else {
                        // No event id can reach it.
                        continue;
                    };
                    events.insert(
                        sub_id,
                        EventDef {
                            name: ev.name,
                            message: ev.message,
                            description: ev.description,
                            arguments: ev
                                .arguments
                                .into_iter()
                                .map(|a| ArgDef {
                                    name: a.name,
                                    ty: a.ty,
                                    description: a.description,
                                })
                                .collect(),
                            kind: ev.kind,
                        },
                    );
                }
                groups.push((name, events));
            }
            for (name, e) in comp.enums.0 {
                let def = EnumDef {
                    base: e.base,
                    is_bitfield: e.is_bitfield,
                    separator: e.separator.unwrap_or_else(|| "|".to_owned()),
                    entries: e
                        .entries
                        .0
                        .into_iter()
                        .map(|(k, v)| (python_int(&k), v.name, v.description))
                        .collect(),
                };
                out.enums
                    .insert(format!("{}::{name}", comp.namespace), Arc::new(def));
            }
            // A component id given twice: the later one replaces the first, in its place.
            let component = Component {
                id,
                namespace: comp.namespace,
                groups,
            };
            match out.components.iter_mut().find(|c| c.id == id) {
                Some(c) => *c = component,
                None => out.components.push(component),
            }
        }
        Ok(out)
    }

    /// The event of this id: component `id >> 24`, then the first group that has sub-id
    /// `id & 0xffffff`.
    pub fn find(&self, id: u32) -> Option<Found<'_>> {
        let comp = i128::from(id >> 24);
        let sub = id & 0xff_ffff;
        let component = self.components.iter().find(|c| c.id == comp)?;
        component.groups.iter().find_map(|(group, events)| {
            events.get(&sub).map(|event| Found {
                component,
                group,
                event,
            })
        })
    }

    /// The enum an argument type names, for an event of `namespace`.
    pub fn enum_of(&self, ty: &str, namespace: &str) -> Option<&Arc<EnumDef>> {
        if ty.contains("::") {
            self.enums.get(ty)
        } else {
            self.enums.get(&format!("{namespace}::{ty}"))
        }
    }

    /// Events defined, over all components and groups.
    pub fn len(&self) -> usize {
        self.components
            .iter()
            .flat_map(|c| &c.groups)
            .map(|(_, events)| events.len())
            .sum()
    }

    /// Whether no event is defined.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Why a metadata JSON could not be read.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DefinitionsError {
    /// Not the JSON of an events metadata.
    #[error("events metadata: {0}")]
    Json(serde_json::Error),
    /// A version this reader does not know.
    #[error("events metadata: unexpected version {0}")]
    Version(f64),
    /// A component or event key that is not an integer.
    #[error("events metadata: key `{0}` is not an integer")]
    Key(String),
}

/// The pairs of a JSON object, in document order.
struct Ordered<T>(Vec<(String, T)>);

impl<T> Default for Ordered<T> {
    fn default() -> Ordered<T> {
        Ordered(Vec::new())
    }
}

impl<'de, T: Deserialize<'de>> Deserialize<'de> for Ordered<T> {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Ordered<T>, D::Error> {
        struct V<T>(PhantomData<T>);
        impl<'de, T: Deserialize<'de>> Visitor<'de> for V<T> {
            type Value = Ordered<T>;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("an object")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Ordered<T>, A::Error> {
                let mut out: Vec<(String, T)> = Vec::new();
                while let Some((k, v)) = map.next_entry::<String, T>()? {
                    // A key given twice: the later value, in the first one's place (as a
                    // Python dict keeps it).
                    match out.iter_mut().find(|(key, _)| *key == k) {
                        Some(entry) => entry.1 = v,
                        None => out.push((k, v)),
                    }
                }
                Ok(Ordered(out))
            }
        }
        d.deserialize_map(V(PhantomData))
    }
}

/// A number, of any JSON number type.
fn number<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    let v = Option::<serde_json::Number>::deserialize(d)?;
    v.map(|n| n.as_f64().ok_or_else(|| de::Error::custom("a number")))
        .transpose()
}

#[derive(Deserialize)]
struct RawDefinitions {
    #[serde(default, deserialize_with = "number")]
    version: Option<f64>,
    #[serde(default)]
    components: Ordered<RawComponent>,
}

#[derive(Deserialize)]
struct RawComponent {
    namespace: String,
    #[serde(default)]
    enums: Ordered<RawEnum>,
    #[serde(default)]
    event_groups: Ordered<RawGroup>,
}

#[derive(Deserialize)]
struct RawGroup {
    #[serde(default)]
    events: Option<Ordered<RawEvent>>,
}

#[derive(Deserialize)]
struct RawEvent {
    name: String,
    message: String,
    #[serde(default)]
    description: Option<String>,
    #[serde(default)]
    arguments: Vec<RawArg>,
    #[serde(default, rename = "type")]
    kind: Option<String>,
}

#[derive(Deserialize)]
struct RawArg {
    name: String,
    #[serde(rename = "type")]
    ty: String,
    #[serde(default)]
    description: Option<String>,
}

#[derive(Deserialize)]
struct RawEnum {
    #[serde(rename = "type")]
    base: String,
    #[serde(default)]
    is_bitfield: bool,
    #[serde(default)]
    separator: Option<String>,
    #[serde(default)]
    entries: Ordered<RawEntry>,
}

#[derive(Deserialize)]
struct RawEntry {
    #[serde(default)]
    name: String,
    #[serde(default)]
    description: Option<String>,
}
