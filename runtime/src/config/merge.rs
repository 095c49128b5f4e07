//! Layering TOML: a user's table overlaid on the preset's, rejecting keys the preset
//! does not have and values of the wrong type; and the choice keys, whose spellings are
//! checked before the sections are read so that a wrong one is named with its key.

use plant::config::{Choice, ConfigError};

/// `[section] key`, when present, is one of `T`'s spellings; the error names the key and
/// the allowed values.
pub(super) fn check_choice<T: Choice>(
    merged: &toml::Table,
    section: &str,
    key: &str,
) -> Result<(), ConfigError> {
    let Some(toml::Value::Table(t)) = merged.get(section) else {
        return Ok(());
    };
    let full = format!("{section}.{key}");
    match t.get(key) {
        None => Ok(()),
        Some(toml::Value::String(s)) => T::parse(s).map(|_| ()).map_err(|_| {
            ConfigError::new(&full, format!("\"{s}\" is not one of: {}", T::spellings()))
        }),
        Some(v) => Err(ConfigError::new(
            &full,
            format!("{v} must be a string, one of: {}", T::spellings()),
        )),
    }
}

/// The value of a choice key: the command line's, else the file's spelling, else
/// `default`.
pub(super) fn choose<T: Choice>(
    key: &str,
    flag: Option<T>,
    file: Option<String>,
    default: T,
) -> Result<T, ConfigError> {
    match (flag, file) {
        (Some(v), _) => Ok(v),
        (None, Some(s)) => T::parse(&s).map_err(|_| {
            ConfigError::new(key, format!("\"{s}\" is not one of: {}", T::spellings()))
        }),
        (None, None) => Ok(default),
    }
}

/// Sections no preset has, which a user may add whole: `[planning]` (MLAC's actions
/// planned with its learned model) and `[lqr]` (a regulator of that model near the
/// reference). Their keys are checked when the configuration is read.
const OPTIONAL_SECTIONS: [&str; 2] = ["planning", "lqr"];

/// Moves each optional section `user` has and `base` lacks into `base` whole (its keys
/// are checked when the configuration is read, not against a preset's).
pub(super) fn add_optional_sections(base: &mut toml::Table, user: &mut toml::Table) {
    for section in OPTIONAL_SECTIONS {
        if base.contains_key(section) {
            continue;
        }
        if let Some(t) = user.remove(section) {
            base.insert(section.into(), t);
        }
    }
}

/// Keys no preset writes that a user may add to `[actor]` and `[critic]` when they have a
/// learning rate: its schedule (`agent::step_size`; off unless given).
const SCHEDULE_KEYS: [&str; 2] = ["decay_trials", "decay_power"];

/// The sections whose learning rate may follow a schedule.
const SCHEDULED_SECTIONS: [&str; 2] = ["actor", "critic"];

/// Moves each schedule key the user's `[actor]` or `[critic]` has into `base`'s section,
/// if that has a learning rate (`alpha`), as a number; elsewhere (an LSTD critic, a
/// process model) the key stays and [`merge`] names it as unknown.
pub(super) fn add_schedule_keys(
    base: &mut toml::Table,
    user: &mut toml::Table,
) -> Result<(), ConfigError> {
    for section in SCHEDULED_SECTIONS {
        let (Some(toml::Value::Table(b)), Some(toml::Value::Table(u))) =
            (base.get_mut(section), user.get_mut(section))
        else {
            continue;
        };
        if !b.contains_key("alpha") {
            continue;
        }
        for key in SCHEDULE_KEYS {
            let value = match u.remove(key) {
                None => continue,
                Some(toml::Value::Integer(i)) => i as f64,
                Some(toml::Value::Float(f)) => f,
                Some(other) => {
                    return Err(ConfigError::new(
                        &format!("{section}.{key}"),
                        format!("{other} has the wrong type: expected a number"),
                    ));
                }
            };
            b.insert(key.into(), toml::Value::Float(value));
        }
    }
    Ok(())
}

/// Overlays `user` on `base`, rejecting keys `base` does not have.
pub(super) fn merge(
    base: &mut toml::Table,
    user: toml::Table,
    prefix: &str,
) -> Result<(), ConfigError> {
    for (k, v) in user {
        let key = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        let Some(slot) = base.get_mut(&k) else {
            return Err(unknown_key(base, &key, prefix));
        };
        match (slot, v) {
            (toml::Value::Table(b), toml::Value::Table(u)) => merge(b, u, &key)?,
            (toml::Value::Table(_), other) => {
                return Err(ConfigError::new(
                    &key,
                    format!("must be a table, not {other}"),
                ));
            }
            (slot, v) => overwrite(slot, v, &key)?,
        }
    }
    Ok(())
}

/// The error for `key`, which the table `known` (at `prefix`) does not have: it lists
/// the keys allowed there.
fn unknown_key(known: &toml::Table, key: &str, prefix: &str) -> ConfigError {
    let mut keys: Vec<&str> = known.keys().map(String::as_str).collect();
    keys.sort();
    let place = if prefix.is_empty() {
        "at the top level".to_string()
    } else {
        format!("in [{prefix}]")
    };
    let schedule = if SCHEDULED_SECTIONS.contains(&prefix) && known.contains_key("alpha") {
        format!(
            "; and the learning rate's schedule: {}",
            SCHEDULE_KEYS.join(", ")
        )
    } else {
        String::new()
    };
    ConfigError::new(
        key,
        format!(
            "unknown key; the keys allowed {place} are: {}{schedule}",
            keys.join(", ")
        ),
    )
}

/// Sets the value at `key` to `v`, which must be of its type (an integer where a float
/// is expected becomes that float).
fn overwrite(slot: &mut toml::Value, v: toml::Value, key: &str) -> Result<(), ConfigError> {
    if std::mem::discriminant(slot) != std::mem::discriminant(&v)
        && !matches!(
            (&*slot, &v),
            (toml::Value::Float(_), toml::Value::Integer(_))
        )
    {
        return Err(ConfigError::new(
            key,
            format!(
                "{v} has the wrong type: expected a {} like {slot}",
                slot.type_str()
            ),
        ));
    }
    *slot = match (&*slot, v) {
        (toml::Value::Float(_), toml::Value::Integer(i)) => toml::Value::Float(i as f64),
        (_, v) => v,
    };
    Ok(())
}
