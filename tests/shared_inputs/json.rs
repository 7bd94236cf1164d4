//! Accessors for the JSON `scripts/mitsuba_scene_params.py` prints (read with `serde_json`)
//! that panic naming what they expected: a test reads a fixed layout, and a value of another
//! shape is the script and the test disagreeing, to be reported, not handled.

pub use serde_json::Value as Json;

pub trait Fields {
    /// The member `key` of an object; panics naming the key when there is none.
    fn field(&self, key: &str) -> &Json;
    fn members(&self) -> &serde_json::Map<String, Json>;
    fn items(&self) -> &[Json];
    fn number(&self) -> f64;
    fn string(&self) -> &str;
    /// An array of numbers.
    fn numbers(&self) -> Vec<f64>;
}

impl Fields for Json {
    fn field(&self, key: &str) -> &Json {
        self.get(key)
            .unwrap_or_else(|| panic!("no \"{key}\" in {self:?}"))
    }

    fn members(&self) -> &serde_json::Map<String, Json> {
        self.as_object()
            .unwrap_or_else(|| panic!("expected an object, found {self:?}"))
    }

    fn items(&self) -> &[Json] {
        self.as_array()
            .unwrap_or_else(|| panic!("expected an array, found {self:?}"))
    }

    fn number(&self) -> f64 {
        self.as_f64()
            .unwrap_or_else(|| panic!("expected a number, found {self:?}"))
    }

    fn string(&self) -> &str {
        self.as_str()
            .unwrap_or_else(|| panic!("expected a string, found {self:?}"))
    }

    fn numbers(&self) -> Vec<f64> {
        self.items().iter().map(Fields::number).collect()
    }
}
