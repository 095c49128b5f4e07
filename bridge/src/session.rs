//! The Zenoh session of each side: where it listens or connects, who may connect, and
//! which keys may cross.
//!
//! The driver's side listens and holds the credentials dictionary: a peer without a
//! listed user and password cannot open a session with it (Zenoh's user-password
//! authentication), and a peer that can may only put commands and pings for this one
//! driver and subscribe to its info, samples and pongs (Zenoh's access control, default
//! deny). The rig's side connects with one user and password and retries while the link
//! is down. Scouting is off: the bridges meet only at the endpoint they are given.

use std::path::{Path, PathBuf};

use zenoh::{Config, Session, Wait};

use crate::error::{Credentials, Error, Result, zenoh};

use crate::message::{Topic, check_user};

/// Where a bridge meets the other and with what.
#[derive(Clone, Debug)]
pub struct Network {
    /// A Zenoh endpoint: the driver's side listens on it (e.g. `tcp/0.0.0.0:7447`), the
    /// rig's side connects to it (e.g. `tcp/192.168.1.20:7447`).
    pub endpoint: String,
    /// `user:password` lines: on the driver's side every user that may connect; on the
    /// rig's side its own (the first line).
    pub credentials: PathBuf,
    /// A Zenoh configuration file (JSON5) to start from, e.g. for TLS endpoints and
    /// certificates; the bridge sets the mode, endpoints, authentication, access control
    /// and scouting over it.
    pub zenoh_config: Option<PathBuf>,
    /// How long the link may stay silent before the session closes it (ms): Zenoh's
    /// link lease.
    pub lease_ms: u64,
}

/// The users and passwords of a credentials file, checked: one `user:password` per
/// line, neither empty, each trimmed; blank lines skipped. No comments: Zenoh reads the
/// driver's side's file itself, by these same rules.
pub fn read_credentials(path: &Path) -> Result<Vec<(String, String)>> {
    let text = std::fs::read_to_string(path).map_err(file("credentials file", path))?;
    owner_only(path, "credentials file")?;
    let refused = |problem| Error::Credentials {
        path: path.to_owned(),
        problem,
    };
    let mut found = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        match line.split_once(':').map(|(u, p)| (u.trim(), p.trim())) {
            Some((u, p)) if !u.is_empty() && !p.is_empty() && !u.contains(char::is_whitespace) => {
                found.push((u.to_string(), p.to_string()))
            }
            _ => return Err(refused(Credentials::Line(i + 1))),
        }
    }
    if found.is_empty() {
        return Err(refused(Credentials::Empty));
    }
    Ok(found)
}

/// The Zenoh configuration's keys that name a private key file.
const PRIVATE_KEY_FILES: [&str; 3] = [
    "transport/link/tls/listen_private_key",
    "transport/link/tls/connect_private_key",
    "transport/auth/pubkey/private_key_file",
];

/// What in a Zenoh configuration file makes the file itself a secret: a private key
/// written into it.
const INLINE_PRIVATE_KEYS: [&str; 2] = ["private_key_base64", "private_key_pem"];

/// Refuses a secret file — credentials, a private key — that others than its owner may
/// read or write, as ssh does with its keys: one line naming the file, its mode and the
/// fix.
fn owner_only(path: &Path, what: &str) -> Result<()> {
    use std::os::unix::fs::PermissionsExt;
    let mode = std::fs::metadata(path)
        .map_err(file(what, path))?
        .permissions()
        .mode()
        & 0o777;
    if mode & 0o077 != 0 {
        return Err(Error::OpenSecret {
            what: what.to_string(),
            path: path.to_owned(),
            mode,
        });
    }
    Ok(())
}

/// An error reading `path`, the `what` of the bridge.
fn file<'a>(what: &'a str, path: &'a Path) -> impl FnOnce(std::io::Error) -> Error + 'a {
    move |error| Error::File {
        what: what.to_string(),
        path: path.to_owned(),
        error,
    }
}

/// Refuses the private keys configuration `c` names (TLS, public-key authentication), and
/// the configuration file `file` if it holds a private key itself, when others than
/// their owner may read them.
fn private_keys_owner_only(c: &Config, file: &Path) -> Result<()> {
    for key in PRIVATE_KEY_FILES {
        let value = c.get_json(key).map_err(|e| Error::Config {
            key: key.to_string(),
            error: e.to_string(),
        })?;
        let path: Option<String> = serde_json::from_str(&value).map_err(|e| Error::Config {
            key: format!("{key} = {value}"),
            error: e.to_string(),
        })?;
        if let Some(path) = path {
            owner_only(Path::new(&path), "private key")?;
        }
    }
    let text = std::fs::read_to_string(file).map_err(self::file("Zenoh configuration", file))?;
    if INLINE_PRIVATE_KEYS.iter().any(|k| text.contains(k)) {
        owner_only(file, "Zenoh configuration (it holds a private key)")?;
    }
    Ok(())
}

/// The users of the credentials file, checked to name keys ([`check_user`]).
fn users(net: &Network) -> Result<Vec<(String, String)>> {
    let users = read_credentials(&net.credentials)?;
    for (u, _) in &users {
        check_user(u).map_err(|problem| Error::Credentials {
            path: net.credentials.clone(),
            problem,
        })?;
    }
    Ok(users)
}

/// The user this side connects as: the first of the credentials file.
pub fn own_user(net: &Network) -> Result<String> {
    Ok(users(net)?.swap_remove(0).0)
}

/// Opens the driver's side's session: listens on the endpoint, admits the users of the
/// credentials file, lets them reach driver `id`'s topics only, and each its own
/// commands' keys only.
pub fn driver_side(id: &str, net: &Network) -> Result<Session> {
    let users = users(net)?;
    let mut c = base(net)?;
    set(&mut c, "listen/endpoints", &json(&[net.endpoint.as_str()]))?;
    set(&mut c, "connect/endpoints", "[]")?;
    let dictionary = net
        .credentials
        .canonicalize()
        .map_err(file("credentials file", &net.credentials))?;
    set(
        &mut c,
        "transport/auth/usrpwd",
        &format!(
            "{{user: {}, password: {}, dictionary_file: {}}}",
            json_str(&users[0].0),
            json_str(&users[0].1),
            json_str(&dictionary.to_string_lossy())
        ),
    )?;
    let names: Vec<&str> = users.iter().map(|(u, _)| u.as_str()).collect();
    set(&mut c, "access_control", &access_control(id, &names))?;
    open(c, &net.endpoint, "listen on")
}

/// Opens the rig's side's session: connects to the endpoint as the first user of the
/// credentials file, and keeps reconnecting while the link is down.
pub fn rig_side(net: &Network) -> Result<Session> {
    connecting(net, Some(users(net)?.swap_remove(0)))
}

/// Opens a probe's session: as the rig's side, or without credentials (`anonymous`).
pub fn probe_side(net: &Network, anonymous: bool) -> Result<Session> {
    match anonymous {
        true => connecting(net, None),
        false => rig_side(net),
    }
}

fn connecting(net: &Network, user: Option<(String, String)>) -> Result<Session> {
    let mut c = base(net)?;
    set(&mut c, "listen/endpoints", "[]")?;
    set(&mut c, "connect/endpoints", &json(&[net.endpoint.as_str()]))?;
    if let Some((user, password)) = user {
        set(
            &mut c,
            "transport/auth/usrpwd",
            &format!(
                "{{user: {}, password: {}}}",
                json_str(&user),
                json_str(&password)
            ),
        )?;
    }
    open(c, &net.endpoint, "connect to")
}

/// What both sides share: peers that only meet at the given endpoint, a short lease,
/// reconnection without end.
fn base(net: &Network) -> Result<Config> {
    let mut c = match &net.zenoh_config {
        Some(p) => {
            let c = Config::from_file(p).map_err(|e| Error::Config {
                key: p.display().to_string(),
                error: e.to_string(),
            })?;
            private_keys_owner_only(&c, p)?;
            c
        }
        None => Config::default(),
    };
    set(&mut c, "mode", "\"peer\"")?;
    set(&mut c, "scouting/multicast/enabled", "false")?;
    set(&mut c, "scouting/gossip/enabled", "false")?;
    set(&mut c, "transport/link/tx/lease", &net.lease_ms.to_string())?;
    set(&mut c, "transport/link/tx/keep_alive", "4")?;
    set(&mut c, "connect/timeout_ms", "-1")?;
    set(&mut c, "connect/exit_on_failure", "false")?;
    set(
        &mut c,
        "connect/retry",
        "{period_init_ms: 100, period_max_ms: 500, period_increase_factor: 2}",
    )?;
    Ok(c)
}

/// Default deny; the users may put pings of driver `id` and each user its own commands
/// and claims (`command/<user>`, `claim/<user>`: the key names who commands), subscribe
/// to its info, samples, pongs and refusals, and receive those (and this side's
/// subscriptions to the commands, claims and pings may reach them).
fn access_control(id: &str, users: &[&str]) -> String {
    let keys = |topics: &[Topic]| {
        let k: Vec<String> = topics.iter().map(|t| t.key(id)).collect();
        json(&k.iter().map(String::as_str).collect::<Vec<_>>())
    };
    let from_driver = keys(&[Topic::Info, Topic::Sample, Topic::Pong, Topic::Refused]);
    let to_driver = keys(&[Topic::Command, Topic::Claim, Topic::Ping]);
    let pings = keys(&[Topic::Ping]);
    let (mut rules, mut subjects, mut policies) = (String::new(), String::new(), String::new());
    for (i, user) in users.iter().enumerate() {
        let own = [Topic::Command, Topic::Claim].map(|t| t.key_of(id, user));
        let own = json(&own.iter().map(String::as_str).collect::<Vec<_>>());
        rules += &format!(
            "    {{ id: \"puts-{i}\", messages: [\"put\"], flows: [\"ingress\"], permission: \"allow\", key_exprs: {own} }},\n"
        );
        subjects += &format!(
            "    {{ id: \"user-{i}\", usernames: {} }},\n",
            json(&[user])
        );
        policies += &format!("    {{ rules: [\"puts-{i}\"], subjects: [\"user-{i}\"] }},\n");
    }
    format!(
        r#"{{
  enabled: true,
  default_permission: "deny",
  rules: [
    {{ id: "rig-pings", messages: ["put"], flows: ["ingress"], permission: "allow", key_exprs: {pings} }},
    {{ id: "driver-puts", messages: ["put"], flows: ["egress"], permission: "allow", key_exprs: {from_driver} }},
    {{ id: "rig-subscribes", messages: ["declare_subscriber"], flows: ["ingress"], permission: "allow", key_exprs: {from_driver} }},
    {{ id: "driver-subscribes", messages: ["declare_subscriber"], flows: ["egress"], permission: "allow", key_exprs: {to_driver} }},
{rules}  ],
  subjects: [
    {{ id: "rigs", usernames: {users} }},
{subjects}  ],
  policies: [
    {{ rules: ["rig-pings", "driver-puts", "rig-subscribes", "driver-subscribes"], subjects: ["rigs"] }},
{policies}  ],
}}"#,
        users = json(users)
    )
}

fn open(c: Config, endpoint: &str, what: &str) -> Result<Session> {
    zenoh::open(c)
        .wait()
        .map_err(zenoh(|| format!("cannot {what} {endpoint}")))
}

fn set(c: &mut Config, key: &str, value: &str) -> Result<()> {
    c.insert_json5(key, value).map_err(|e| Error::Config {
        key: format!("{key} = {value}"),
        error: e.to_string(),
    })
}

fn json(items: &[&str]) -> String {
    let quoted: Vec<String> = items.iter().map(|s| json_str(s)).collect();
    format!("[{}]", quoted.join(", "))
}

fn json_str(s: &str) -> String {
    format!("{s:?}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn credentials_files_are_checked_line_by_line() {
        let dir = std::env::temp_dir().join(format!("bridge-cred-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = dir.join("users.txt");
        std::fs::write(&f, "rig:s3cret\n\n lab : pa:ss \n").unwrap();
        chmod(&f, 0o600);
        assert_eq!(
            read_credentials(&f).unwrap(),
            [
                ("rig".into(), "s3cret".into()),
                ("lab".into(), "pa:ss".into())
            ]
        );
        std::fs::write(&f, "rig\n").unwrap();
        let e = read_credentials(&f).unwrap_err().to_string();
        assert!(
            e.contains("users.txt line 1: expected `user:password`"),
            "{e}"
        );
        std::fs::write(&f, "# rig:s3cret\n").unwrap();
        let e = read_credentials(&f).unwrap_err().to_string();
        assert!(e.contains("line 1: expected `user:password`"), "{e}");
        std::fs::write(&f, "\n").unwrap();
        assert!(
            read_credentials(&f)
                .unwrap_err()
                .to_string()
                .contains("no `user:password` line")
        );
        let e = format!("{:#}", read_credentials(&dir.join("missing")).unwrap_err());
        assert!(e.contains("missing") && e.contains("No such file"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    fn chmod(path: &Path, mode: u32) {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(path, std::fs::Permissions::from_mode(mode)).unwrap();
    }

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("bridge-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    /// The one line refusing `what` at `path` of `mode`.
    fn refusal(what: &str, path: &Path, mode: u32) -> String {
        let p = path.display();
        format!(
            "{what} {p} is open to others than its owner (mode {mode:04o}); refused: `chmod 600 {p}`"
        )
    }

    #[test]
    fn credentials_open_to_group_or_others_are_refused() {
        let dir = scratch("cred-mode");
        let f = dir.join("lab.users");
        std::fs::write(&f, "rig:s3cret\n").unwrap();
        for mode in [0o644, 0o640, 0o604, 0o620] {
            chmod(&f, mode);
            let e = read_credentials(&f).unwrap_err().to_string();
            assert_eq!(e, refusal("credentials file", &f, mode));
        }
        chmod(&f, 0o600);
        assert_eq!(read_credentials(&f).unwrap().len(), 1);
        chmod(&f, 0o400);
        assert_eq!(read_credentials(&f).unwrap().len(), 1);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn private_keys_open_to_group_or_others_are_refused() {
        let dir = scratch("key-mode");
        let key = dir.join("key.pem");
        std::fs::write(&key, "-----BEGIN PRIVATE KEY-----\n").unwrap();
        let conf = dir.join("driver.json5");
        std::fs::write(
            &conf,
            format!("{{ transport: {{ link: {{ tls: {{ listen_private_key: {key:?}, listen_certificate: \"cert.pem\" }} }} }} }}"),
        )
        .unwrap();
        let net = Network {
            endpoint: "tls/127.0.0.1:7447".into(),
            credentials: dir.join("unused"),
            zenoh_config: Some(conf.clone()),
            lease_ms: 1000,
        };
        for mode in [0o644, 0o640] {
            chmod(&key, mode);
            let e = base(&net).unwrap_err().to_string();
            assert_eq!(e, refusal("private key", &key, mode));
        }
        chmod(&key, 0o600);
        base(&net).unwrap();
        // A key written into the configuration makes the configuration a secret.
        std::fs::write(
            &conf,
            "{ transport: { link: { tls: { listen_private_key_base64: \"c2VjcmV0\" } } } }",
        )
        .unwrap();
        chmod(&conf, 0o644);
        let e = base(&net).unwrap_err().to_string();
        assert!(e.contains("driver.json5") && e.contains("mode 0644"), "{e}");
        chmod(&conf, 0o600);
        base(&net).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn the_access_control_names_this_drivers_keys_only() {
        let acl = access_control("qube", &["rig"]);
        let c = {
            let mut c = Config::default();
            c.insert_json5("access_control", &acl).unwrap();
            c
        };
        assert_eq!(c.get_json("access_control/enabled").unwrap(), "true");
        assert!(
            acl.contains(r#"["rig/driver/qube/command/*", "rig/driver/qube/claim/*", "rig/driver/qube/ping"]"#),
            "{acl}"
        );
        assert!(acl.contains(
            r#"["rig/driver/qube/info", "rig/driver/qube/sample", "rig/driver/qube/pong", "rig/driver/qube/refused"]"#
        ));
        // Each user puts commands under its own name only.
        assert!(acl.contains(
            r#"key_exprs: ["rig/driver/qube/command/rig", "rig/driver/qube/claim/rig"]"#
        ));
        assert!(acl.contains(r#"{ rules: ["puts-0"], subjects: ["user-0"] }"#));
        assert!(!acl.contains("**"));
    }
}
