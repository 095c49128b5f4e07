//! The messages' schema: flat fields of JSON type `integer` or `number`
//! ([`Field`], [`FieldKind`]), their values ([`Value`]), and a channel's JSON Schema.

/// The JSON type of one message field.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FieldKind {
    /// JSON Schema `integer`: a [`Value::Int`].
    Integer,
    /// JSON Schema `number`: a [`Value::Num`] (or a [`Value::Int`]); NaN and ±∞ become `null`.
    Number,
}

/// One flat field of a channel's messages.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Field {
    /// The JSON key, e.g. `seq` or `x_0`.
    pub name: String,
    /// The JSON type.
    pub kind: FieldKind,
}

impl Field {
    /// An `integer` field called `name`.
    pub fn integer(name: &str) -> Field {
        Field {
            name: name.to_owned(),
            kind: FieldKind::Integer,
        }
    }

    /// A `number` field called `name`.
    pub fn number(name: &str) -> Field {
        Field {
            name: name.to_owned(),
            kind: FieldKind::Number,
        }
    }

    /// An array field flattened: `Field::array("x", 3, FieldKind::Number)` is the fields
    /// `x_0, x_1, x_2`, in that order.
    pub fn array(name: &str, len: usize, kind: FieldKind) -> Vec<Field> {
        (0..len)
            .map(|i| Field {
                name: format!("{name}_{i}"),
                kind,
            })
            .collect()
    }
}

/// One field value of a message, in the order of the channel's fields.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value {
    /// An integer (counters, flags, trial numbers).
    Int(u64),
    /// A real number; NaN and ±∞ are written as `null`.
    Num(f64),
}

/// The JSON Schema of a channel: an object with flat `integer`/`number` properties, in
/// field order.
pub(super) fn json_schema(fields: &[Field]) -> Vec<u8> {
    let mut s = String::from(r#"{"type":"object","properties":{"#);
    for (i, f) in fields.iter().enumerate() {
        if i > 0 {
            s.push(',');
        }
        let kind = match f.kind {
            FieldKind::Integer => "integer",
            FieldKind::Number => "number",
        };
        s.push_str(&json_string(&f.name));
        s.push_str(r#":{"type":""#);
        s.push_str(kind);
        s.push_str(r#""}"#);
    }
    s.push_str("}}");
    s.into_bytes()
}

/// `s` as a JSON string literal, quoted and escaped.
pub(super) fn json_string(s: &str) -> String {
    serde_json::to_string(s).expect("a string always serialises")
}
