//! `docs/driver.md` is the contract a driver author reads: its layout tables, service
//! settings and constants must be the Rust structs' (and the Python package's messages
//! must be the doc's), so that the page cannot drift from the code.

use std::collections::BTreeMap;
use std::mem::{align_of, offset_of, size_of};

use driver::contract::{
    DRIVER_QOS, DriverCommand, DriverInfo, DriverSample, ending, kind, provides, status,
};
use wire::type_name_of;

const DOC: &str = include_str!("../../docs/driver.md");
const PY_MESSAGES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../python/rigkit/messages.py");

/// One row of a layout table: field, offset, size, type.
type Row = (String, usize, usize, String);

/// A struct as the doc describes it: size, alignment, rows.
#[derive(Debug, PartialEq)]
struct Layout {
    size: usize,
    align: usize,
    rows: Vec<Row>,
}

fn field_size<T, F>(_: fn(&T) -> &F) -> usize {
    size_of::<F>()
}

/// `(type name, layout)` of a Rust struct, fields listed in declaration order; the type
/// column is the Rust type as written.
macro_rules! layout {
    ($t:ty { $($f:ident : $ty:literal),* $(,)? }) => {
        (
            type_name_of::<$t>().to_string(),
            Layout {
                size: size_of::<$t>(),
                align: align_of::<$t>(),
                rows: vec![$((
                    stringify!($f).to_string(),
                    offset_of!($t, $f),
                    field_size(|s: &$t| &s.$f),
                    $ty.to_string(),
                )),*],
            },
        )
    };
}

fn rust_layouts() -> BTreeMap<String, Layout> {
    let all = [
        layout!(DriverInfo {
            version: "u64",
            task: "[u8; 32]",
            task_hash: "u64",
            clock: "u64",
            n_x: "u64",
            n_u: "u64",
            period_ns: "u64",
            time_scale: "f64",
            u_min: "[f64; 4]",
            u_max: "[f64; 4]",
            watchdog_periods: "u64",
            t_start_ns: "u64",
            t_publish_ns: "u64",
            provides: "u64",
        }),
        layout!(DriverSample {
            seq: "u64",
            t_sample_ns: "u64",
            t_publish_ns: "u64",
            status: "u64",
            reset_id: "u64",
            last_command: "u64",
            n_x: "u64",
            n_u: "u64",
            x: "[f64; 8]",
            u_applied: "[f64; 4]",
            clamped: "u64",
            rejected: "u64",
            watchdog_trips: "u64",
            reward: "f64",
            ending: "u64",
        }),
        layout!(DriverCommand {
            seq: "u64",
            kind: "u64",
            sample_seq: "u64",
            t_publish_ns: "u64",
            n_u: "u64",
            u: "[f64; 4]",
            n_x: "u64",
            x0: "[f64; 8]",
        }),
    ];
    for (name, l) in &all {
        // The listed fields cover the whole struct: a field added to the struct but not
        // here (and so not checked against the doc) fails this.
        let covered: usize = l.rows.iter().map(|r| r.2).sum();
        assert_eq!(
            covered, l.size,
            "{name}: fields listed in this test cover the struct"
        );
    }
    all.into_iter().collect()
}

/// The cells of a table row `| a | b | ... |`, trimmed, backticks removed.
fn cells(line: &str) -> Vec<String> {
    line.trim()
        .trim_matches('|')
        .split('|')
        .map(|c| c.trim().trim_matches('`').to_string())
        .collect()
}

/// The layout tables of the doc: each `### \`type\` (N bytes, alignment A)` heading and
/// the numeric rows of the table under it.
fn doc_layouts() -> BTreeMap<String, Layout> {
    let mut out = BTreeMap::new();
    let mut current: Option<(String, Layout)> = None;
    for line in DOC.lines() {
        if let Some(rest) = line.strip_prefix("### `") {
            if let Some((name, l)) = current.take() {
                out.insert(name, l);
            }
            let Some((name, tail)) = rest.split_once('`') else {
                continue;
            };
            let numbers: Vec<usize> = tail
                .split(|c: char| !c.is_ascii_digit())
                .filter_map(|t| t.parse().ok())
                .collect();
            if let [size, align] = numbers[..] {
                current = Some((
                    name.to_string(),
                    Layout {
                        size,
                        align,
                        rows: Vec::new(),
                    },
                ));
            }
        } else if line.starts_with("## ") {
            if let Some((name, l)) = current.take() {
                out.insert(name, l);
            }
        } else if let Some((_, l)) = current.as_mut()
            && line.starts_with('|')
        {
            let c = cells(line);
            if let (Ok(offset), Ok(size)) = (c[0].parse(), c[1].parse()) {
                l.rows.push((c[2].clone(), offset, size, c[3].clone()));
            }
        }
    }
    out
}

/// Size of a type as the doc writes it: `u64`, `f64`, `[f64; N]`, `[u8; N]`.
fn size_of_doc_type(t: &str) -> usize {
    match t {
        "u64" | "f64" => 8,
        _ => {
            let inner = t.trim_start_matches('[').trim_end_matches(']');
            let (elem, n) = inner.split_once(';').expect("an array type");
            let n: usize = n.trim().parse().expect("an array length");
            n * match elem.trim() {
                "u8" => 1,
                "u64" | "f64" => 8,
                e => panic!("unknown element type {e}"),
            }
        }
    }
}

#[test]
fn the_docs_layout_tables_are_the_rust_structs() {
    let doc = doc_layouts();
    let rust = rust_layouts();
    assert_eq!(
        doc.keys().collect::<Vec<_>>(),
        rust.keys().collect::<Vec<_>>(),
        "the doc has a layout table for each driver message, under its type name"
    );
    for (name, want) in &rust {
        let got = &doc[name];
        assert_eq!(got, want, "docs/driver.md, table of {name}");
        for (field, _, size, ty) in &got.rows {
            assert_eq!(size_of_doc_type(ty), *size, "{name}.{field}: type {ty}");
        }
    }
}

/// Rows `| \`key\` | value | ...` of the doc, by key.
fn doc_values() -> BTreeMap<String, String> {
    DOC.lines()
        .filter(|l| l.starts_with("| `"))
        .map(cells)
        .filter(|c| c.len() >= 2)
        .map(|c| (c[0].clone(), c[1].clone()))
        .collect()
}

#[test]
fn the_docs_settings_and_constants_are_the_codes() {
    let v = doc_values();
    for (key, want) in [
        ("max_publishers", DRIVER_QOS.max_publishers as u64),
        ("max_subscribers", DRIVER_QOS.max_subscribers as u64),
        ("subscriber_max_buffer_size", DRIVER_QOS.buffer as u64),
        ("READY", status::READY),
        ("RESETTING", status::RESETTING),
        ("WATCHDOG", status::WATCHDOG),
        ("ACTION", kind::ACTION),
        ("RESET", kind::RESET),
        ("PROVIDES_REWARD", provides::REWARD),
        ("TERMINATED", ending::TERMINATED),
        ("TRUNCATED", ending::TRUNCATED),
    ] {
        assert_eq!(v.get(key), Some(&want.to_string()), "docs/driver.md: {key}");
    }
    assert_eq!(
        v.get("enable_safe_overflow").map(String::as_str),
        Some("true")
    );
    for topic in ["info", "sample", "command"] {
        assert!(
            DOC.contains(&format!("`{}`", driver::contract::service("<id>", topic))),
            "the doc names the {topic} service"
        );
    }
}

#[test]
fn the_python_examples_messages_are_the_docs() {
    // Offsets, sizes and type names of the ctypes classes, printed by python3 itself.
    let script = format!(
        r#"
import ctypes, importlib.util
spec = importlib.util.spec_from_file_location("messages", r"{PY_MESSAGES}")
m = importlib.util.module_from_spec(spec); spec.loader.exec_module(m)
for cls in (m.DriverInfo, m.DriverSample, m.DriverCommand):
    print(cls.type_name(), ctypes.sizeof(cls), ctypes.alignment(cls))
    for name, _ in cls._fields_:
        f = getattr(cls, name)
        print(" ", name, f.offset, f.size)
for c in ("READY", "RESETTING", "WATCHDOG", "ACTION", "RESET", "PROVIDES_REWARD", "TERMINATED", "TRUNCATED", "MAX_X", "MAX_U", "VERSION"):
    print("=", c, getattr(m, c))
"#
    );
    let out = match std::process::Command::new("python3")
        .args(["-c", &script])
        .output()
    {
        Ok(o) => o,
        Err(e) => {
            println!("skipped: python3 is not available ({e})");
            return;
        }
    };
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    let mut py: BTreeMap<String, Layout> = BTreeMap::new();
    let mut consts = BTreeMap::new();
    let mut current = String::new();
    for line in text.lines() {
        let w: Vec<&str> = line.split_whitespace().collect();
        if let Some(field) = line.strip_prefix("  ") {
            let w: Vec<&str> = field.split_whitespace().collect();
            let l = py.get_mut(&current).unwrap();
            l.rows.push((
                w[0].to_string(),
                w[1].parse().unwrap(),
                w[2].parse().unwrap(),
                String::new(),
            ));
        } else if w[0] == "=" {
            consts.insert(w[1].to_string(), w[2].parse::<u64>().unwrap());
        } else {
            current = w[0].to_string();
            py.insert(
                current.clone(),
                Layout {
                    size: w[1].parse().unwrap(),
                    align: w[2].parse().unwrap(),
                    rows: Vec::new(),
                },
            );
        }
    }
    let doc = doc_layouts();
    assert_eq!(
        py.keys().collect::<Vec<_>>(),
        doc.keys().collect::<Vec<_>>()
    );
    for (name, want) in &doc {
        let got = &py[name];
        assert_eq!(
            (got.size, got.align),
            (want.size, want.align),
            "messages.py: {name}"
        );
        let strip = |rows: &[Row]| -> Vec<(String, usize, usize)> {
            rows.iter().map(|r| (r.0.clone(), r.1, r.2)).collect()
        };
        assert_eq!(strip(&got.rows), strip(&want.rows), "messages.py: {name}");
    }
    let v = doc_values();
    for c in [
        "READY",
        "RESETTING",
        "WATCHDOG",
        "ACTION",
        "RESET",
        "PROVIDES_REWARD",
        "TERMINATED",
        "TRUNCATED",
    ] {
        assert_eq!(Some(&consts[c].to_string()), v.get(c), "messages.py: {c}");
    }
    assert_eq!(consts["MAX_X"], wire::MAX_X as u64);
    assert_eq!(consts["MAX_U"], wire::MAX_U as u64);
    assert_eq!(consts["VERSION"], driver::contract::VERSION);
}
