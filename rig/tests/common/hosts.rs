//! Two hosts on this machine for the cross-host tests: two network namespaces joined by
//! a veth pair, each with its own shared memory (`/dev/shm`, `/tmp/iceoryx2` on tmpfs in
//! a mount namespace of its own), so iceoryx2 on one cannot see the other's services and
//! only the network joins them. Both read the machine's one monotonic clock.

use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::Duration;

/// One host: a process that holds its namespaces, and its address.
pub struct Host {
    anchor: Child,
    netns: String,
    /// Its address on the veth link.
    pub addr: String,
    /// Its end of the link.
    pub dev: String,
}

impl Host {
    /// `program args…` run on this host.
    pub fn command(&self, program: impl AsRef<Path>) -> Command {
        let mut c = Command::new("nsenter");
        c.arg("--target")
            .arg(self.anchor.id().to_string())
            .args(["--mount", "--net"])
            .arg(program.as_ref());
        c
    }

    /// Waits (at most 10 s) until the anchor has mounted its shared memory and sleeps.
    fn wait_until_anchored(&self) {
        let cmdline = format!("/proc/{}/cmdline", self.anchor.id());
        for _ in 0..1000 {
            if std::fs::read(&cmdline).is_ok_and(|c| c.starts_with(b"sleep")) {
                return;
            }
            std::thread::sleep(Duration::from_millis(10));
        }
        panic!("host {} did not come up", self.netns);
    }

    /// Takes this host's end of the link down (`false`) or up.
    pub fn link(&self, up: bool) {
        run(&[
            "ip",
            "-n",
            &self.netns,
            "link",
            "set",
            &self.dev,
            if up { "up" } else { "down" },
        ]);
    }
}

/// Hosts A (`10.77.N.1`) and B (`10.77.N.2`), removed when dropped.
pub struct Hosts {
    /// The driver's host.
    pub a: Host,
    /// The rig's host.
    pub b: Host,
}

impl Hosts {
    /// Two hosts for test number `n` (distinct per test of a binary: names and subnet),
    /// or `None`, with the reason printed, where this process cannot make them (not
    /// root, no `ip`, `nsenter` or `unshare`, no network namespaces).
    pub fn new(n: u8) -> Option<Self> {
        let root = std::fs::read_to_string("/proc/self/status")
            .unwrap_or_default()
            .lines()
            .any(|l| l.starts_with("Uid:") && l.split_whitespace().nth(1) == Some("0"));
        if !root {
            println!("skipped: making network namespaces needs root");
            return None;
        }
        for tool in ["ip", "nsenter", "unshare"] {
            if Command::new(tool).arg("--version").output().is_err() {
                println!("skipped: no `{tool}` (iproute2, util-linux)");
                return None;
            }
        }
        let tag = format!("{}{n}", std::process::id() % 100_000);
        let (na, nb) = (format!("riga{tag}"), format!("rigb{tag}"));
        let (da, db) = (format!("va{tag}"), format!("vb{tag}"));
        if let Err(e) = try_run(&["ip", "netns", "add", &na]) {
            println!("skipped: cannot make a network namespace: {e}");
            return None;
        }
        run(&["ip", "netns", "add", &nb]);
        run(&[
            "ip", "link", "add", &da, "type", "veth", "peer", "name", &db,
        ]);
        let host = |ns: &str, dev: &str, last: u8| {
            let addr = format!("10.77.{n}.{last}");
            run(&["ip", "link", "set", dev, "netns", ns]);
            run(&[
                "ip",
                "-n",
                ns,
                "addr",
                "add",
                &format!("{addr}/24"),
                "dev",
                dev,
            ]);
            run(&["ip", "-n", ns, "link", "set", dev, "up"]);
            run(&["ip", "-n", ns, "link", "set", "lo", "up"]);
            Host {
                anchor: anchor(ns),
                netns: ns.to_string(),
                addr,
                dev: dev.to_string(),
            }
        };
        let hosts = Self {
            a: host(&na, &da, 1),
            b: host(&nb, &db, 2),
        };
        for h in [&hosts.a, &hosts.b] {
            h.wait_until_anchored();
        }
        Some(hosts)
    }
}

impl Hosts {
    /// A third host on B's network (its address, its link) with shared memory of its
    /// own: a second rig workstation behind B's address.
    pub fn beside_b(&self) -> Host {
        let h = Host {
            anchor: anchor(&self.b.netns),
            netns: self.b.netns.clone(),
            addr: self.b.addr.clone(),
            dev: self.b.dev.clone(),
        };
        h.wait_until_anchored();
        h
    }
}

impl Drop for Host {
    fn drop(&mut self) {
        let _ = self.anchor.kill();
        let _ = self.anchor.wait();
    }
}

impl Drop for Hosts {
    fn drop(&mut self) {
        for h in [&mut self.a, &mut self.b] {
            let _ = h.anchor.kill();
            let _ = h.anchor.wait();
            let _ = try_run(&["ip", "netns", "del", &h.netns]);
        }
    }
}

/// A process in network namespace `ns` and a mount namespace of its own with fresh
/// tmpfs on `/dev/shm` and `/tmp/iceoryx2`; it sleeps until killed.
fn anchor(ns: &str) -> Child {
    Command::new("ip")
        .args(["netns", "exec", ns, "unshare", "--mount", "--propagation", "private"])
        .args(["sh", "-c"])
        .arg("mount -t tmpfs tmpfs /dev/shm && mkdir -p /tmp/iceoryx2 && mount -t tmpfs tmpfs /tmp/iceoryx2 && exec sleep infinity")
        .stdin(Stdio::null())
        .spawn()
        .expect("ip netns exec")
}

fn try_run(args: &[&str]) -> Result<(), String> {
    let out = Command::new(args[0])
        .args(&args[1..])
        .output()
        .map_err(|e| e.to_string())?;
    match out.status.success() {
        true => Ok(()),
        false => Err(String::from_utf8_lossy(&out.stderr).trim().to_string()),
    }
}

fn run(args: &[&str]) {
    if let Err(e) = try_run(args) {
        panic!("{}: {e}", args.join(" "));
    }
}

impl Host {
    /// `nft ARGS` in this host's network namespace.
    fn nft(&self, args: &[&str]) {
        let mut all = vec!["ip", "netns", "exec", &self.netns, "nft"];
        all.extend(args);
        run(&all);
    }

    /// Adds nftables table `table` with an output chain dropping what `rule` matches.
    fn drop_out(&self, table: &str, rule: &str) {
        self.nft(&["add", "table", "inet", table]);
        self.nft(&[
            "add",
            "chain",
            "inet",
            table,
            "out",
            "{ type filter hook output priority 0; }",
        ]);
        let mut args = vec!["add", "rule", "inet", table, "out"];
        args.extend(rule.split(' '));
        self.nft(&args);
    }

    /// Drops `percent` % of the TCP packets this host sends, at random (nftables).
    pub fn lose(&self, percent: u32) {
        self.drop_out(
            "rigloss",
            &format!("meta l4proto tcp numgen random mod 100 < {percent} counter drop"),
        );
    }

    /// Drops the TCP packets with data this host sends to `port` at `addr` beyond
    /// `kbytes` kB/s (nftables; the acknowledgements of what it receives all go): its
    /// sending is throttled, its receiving is not.
    pub fn throttle(&self, addr: &str, port: u16, kbytes: u32) {
        // Packets of one segment each (the policer sees what is sent, not 64 kB of
        // segments to come), and a loss-based congestion control, which backs off before
        // a policer (BBR, the machine's default here, goes on sending into it).
        run(&[
            "ip",
            "-n",
            &self.netns,
            "link",
            "set",
            "dev",
            &self.dev,
            "gso_max_segs",
            "1",
        ]);
        run(&[
            "ip",
            "netns",
            "exec",
            &self.netns,
            "sysctl",
            "-q",
            "net.ipv4.tcp_congestion_control=reno",
        ]);
        self.drop_out(
            "rigthrottle",
            &format!(
                "ip daddr {addr} tcp dport {port} ip length > 80 limit rate over {kbytes} kbytes/second counter drop"
            ),
        );
    }

    /// Drops every TCP packet this host sends (`true`, nftables), or none again: the
    /// link cut while the interfaces stay up.
    pub fn cut(&self, on: bool) {
        match on {
            true => self.drop_out("rigcut", "meta l4proto tcp counter drop"),
            false => self.nft(&["delete", "table", "inet", "rigcut"]),
        }
    }

    /// A TCP relay on this host, listening on `listen` (`addr:port`) and forwarding to
    /// `to`, that holds every chunk `delay` in each direction (in order): a link that
    /// takes `delay` longer each way, where the kernel has no `netem`.
    pub fn relay(&self, listen: &str, to: &str, delay: Duration) {
        let (netns, listen, to) = (self.netns.clone(), listen.to_string(), to.to_string());
        let (ready_tx, ready) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            enter_netns(&netns);
            let listener = std::net::TcpListener::bind(&listen).expect("relay: bind");
            ready_tx.send(()).unwrap();
            for inbound in listener.incoming().flatten() {
                let Ok(outbound) = std::net::TcpStream::connect(&to) else {
                    continue;
                };
                for (from, into) in [
                    (inbound.try_clone().unwrap(), outbound.try_clone().unwrap()),
                    (outbound, inbound),
                ] {
                    std::thread::spawn(move || delayed_copy(from, into, delay));
                }
            }
        });
        ready.recv().expect("relay started");
    }
}

/// Moves this thread (and the threads it starts) into network namespace `name`.
fn enter_netns(name: &str) {
    use std::os::fd::AsRawFd;
    let f = std::fs::File::open(format!("/var/run/netns/{name}")).expect("netns file");
    // SAFETY: setns on an open namespace file descriptor; affects this thread only.
    let r = unsafe { libc::setns(f.as_raw_fd(), libc::CLONE_NEWNET) };
    assert_eq!(r, 0, "setns {name}: {}", std::io::Error::last_os_error());
}

/// Copies `from` to `into`, each chunk written `delay` after it was read.
fn delayed_copy(mut from: std::net::TcpStream, into: std::net::TcpStream, delay: Duration) {
    use std::io::{Read, Write};
    let (tx, rx) = std::sync::mpsc::channel::<(std::time::Instant, Vec<u8>)>();
    let writer = std::thread::spawn(move || {
        let mut into = into;
        for (at, chunk) in rx {
            std::thread::sleep(at.saturating_duration_since(std::time::Instant::now()));
            if into.write_all(&chunk).is_err() {
                break;
            }
        }
        let _ = into.shutdown(std::net::Shutdown::Write);
    });
    let _ = from.set_nodelay(true);
    let mut buf = vec![0u8; 65536];
    while let Ok(n) = from.read(&mut buf) {
        if n == 0
            || tx
                .send((std::time::Instant::now() + delay, buf[..n].to_vec()))
                .is_err()
        {
            break;
        }
    }
    drop(tx);
    let _ = writer.join();
}
