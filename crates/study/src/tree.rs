//! An owned, spanned copy of the parsed TOML, independent of the `toml` crate's types.

use std::ops::Range;

use toml::Spanned;
use toml::de::{DeTable, DeValue};

/// A value with the byte range it came from.
#[derive(Clone, Debug)]
pub(crate) struct Node {
    pub value: Value,
    pub span: Range<usize>,
}

/// A table entry: the key, where the key is written, and its value.
#[derive(Clone, Debug)]
pub(crate) struct Entry {
    pub key: String,
    pub key_span: Range<usize>,
    pub node: Node,
}

#[derive(Clone, Debug)]
pub(crate) enum Value {
    Str(String),
    Int(i64),
    Float(f64),
    Bool(bool),
    Datetime(String),
    Array(Vec<Node>),
    /// Entries in file order.
    Table(Vec<Entry>),
}

impl Value {
    /// The TOML type name, for "expected X, found Y".
    pub fn type_name(&self) -> &'static str {
        match self {
            Value::Str(_) => "a string",
            Value::Int(_) => "an integer",
            Value::Float(_) => "a float",
            Value::Bool(_) => "a boolean",
            Value::Datetime(_) => "a date-time",
            Value::Array(_) => "an array",
            Value::Table(_) => "a table",
        }
    }
}

/// Converts the parser's tree; the error is (byte offset, message) for
/// integers that do not fit in i64.
pub(crate) fn convert_table(t: &DeTable<'_>) -> Result<Vec<Entry>, (usize, String)> {
    let mut out = Vec::with_capacity(t.len());
    for (k, v) in t.iter() {
        out.push(Entry {
            key: k.get_ref().to_string(),
            key_span: k.span(),
            node: convert(v)?,
        });
    }
    out.sort_by_key(|e| (e.key_span.start, e.node.span.start));
    Ok(out)
}

fn convert(v: &Spanned<DeValue<'_>>) -> Result<Node, (usize, String)> {
    let span = v.span();
    let value = match v.get_ref() {
        DeValue::String(s) => Value::Str(s.to_string()),
        DeValue::Integer(i) => {
            let digits = i.as_str().replace('_', "");
            let x = i64::from_str_radix(&digits, i.radix())
                .map_err(|_| (span.start, format!("integer `{i}` does not fit in 64 bits")))?;
            Value::Int(x)
        }
        DeValue::Float(f) => {
            let s = f.as_str().replace('_', "");
            let x = s.parse::<f64>().unwrap_or_else(|_| {
                if s.ends_with("nan") {
                    f64::NAN
                } else if s.starts_with('-') {
                    f64::NEG_INFINITY
                } else {
                    f64::INFINITY
                }
            });
            Value::Float(x)
        }
        DeValue::Boolean(b) => Value::Bool(*b),
        DeValue::Datetime(d) => Value::Datetime(d.to_string()),
        DeValue::Array(a) => Value::Array(a.iter().map(convert).collect::<Result<_, _>>()?),
        DeValue::Table(t) => Value::Table(convert_table(t)?),
    };
    Ok(Node { value, span })
}

/// Canonical text of a table: keys sorted, floats by bit pattern, strings
/// escaped. Comments, whitespace, key order and TOML spelling (inline vs
/// header tables, `1e3` vs `1000.0`) do not change it.
pub(crate) fn canonical(entries: &[Entry], out: &mut String) {
    let mut sorted: Vec<&Entry> = entries.iter().collect();
    sorted.sort_by(|a, b| a.key.cmp(&b.key));
    out.push('{');
    for e in sorted {
        out.push_str(&format!("{:?}=", e.key));
        canonical_value(&e.node.value, out);
        out.push(';');
    }
    out.push('}');
}

fn canonical_value(v: &Value, out: &mut String) {
    match v {
        Value::Str(s) => out.push_str(&format!("s{s:?}")),
        Value::Int(i) => out.push_str(&format!("i{i}")),
        Value::Float(x) => out.push_str(&format!("f{:016x}", x.to_bits())),
        Value::Bool(b) => out.push_str(if *b { "true" } else { "false" }),
        Value::Datetime(d) => out.push_str(&format!("d{d:?}")),
        Value::Array(a) => {
            out.push('[');
            for n in a {
                canonical_value(&n.value, out);
                out.push(',');
            }
            out.push(']');
        }
        Value::Table(t) => canonical(t, out),
    }
}
