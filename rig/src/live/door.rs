//! The protocol's two names. A viewer and the server agree on the Foxglove WebSocket
//! protocol as a WebSocket subprotocol, by name: `foxglove.websocket.v1`, the name of the
//! protocol's specification (offered by `@foxglove/ws-protocol`'s client and by Lichtblick
//! and Foxglove releases before late 2025), or `foxglove.sdk.v1`, the same messages under the
//! name the Foxglove SDK gives them. The `foxglove` crate's server accepts only the new name
//! (and `foxglove.sdk.v1.1`), and refuses a client offering only the old one with HTTP 400.
//!
//! The [`Door`] listens where the user asked and hands each connection to the crate's
//! server, which listens on this host's loopback address only. A handshake offering the old
//! name and none of the new ones is renamed on the way in (the request's
//! `Sec-WebSocket-Protocol`) and on the way out (the server's choice), so that each client
//! hears the name it offered; every other request, and every byte after the handshake,
//! passes unchanged.

use std::collections::HashMap;
use std::io::{self, Read, Write};
use std::net::{Ipv4Addr, Ipv6Addr, Shutdown, SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

/// The protocol's name in its specification.
pub const SPEC_NAME: &str = "foxglove.websocket.v1";
/// The names the `foxglove` crate's server accepts.
pub const SDK_NAMES: [&str; 2] = ["foxglove.sdk.v1", "foxglove.sdk.v1.1"];
/// The header that names the subprotocols.
const HEADER: &str = "sec-websocket-protocol";
/// The longest handshake read; a longer one is cut off.
const HEAD_LIMIT: usize = 64 * 1024;
/// How long a client may take to send its handshake.
const HEAD_TIMEOUT: Duration = Duration::from_secs(10);

/// The connections passing through, by number: both ends, to end them on close.
type Open = Mutex<HashMap<u64, [TcpStream; 2]>>;

/// The listening end in front of the crate's server.
pub struct Door {
    addr: SocketAddr,
    closing: Arc<AtomicBool>,
    open: Arc<Open>,
    accepting: JoinHandle<()>,
}

impl Door {
    /// Listens on `addr` and passes each connection to the server at `server`.
    pub fn open(addr: SocketAddr, server: SocketAddr) -> io::Result<Door> {
        let listener = TcpListener::bind(addr)?;
        let addr = listener.local_addr()?;
        let closing = Arc::new(AtomicBool::new(false));
        let open: Arc<Open> = Arc::default();
        let accepting = {
            let (closing, open) = (closing.clone(), open.clone());
            std::thread::Builder::new()
                .name("live view door".into())
                .spawn(move || accept(&listener, server, &closing, &open))?
        };
        Ok(Door {
            addr,
            closing,
            open,
            accepting,
        })
    }

    /// Where it listens.
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// Stops listening and ends every connection still open.
    pub fn close(self) {
        self.closing.store(true, Ordering::SeqCst);
        // Wake the accepting thread with a connection of our own.
        let mut wake = self.addr;
        if wake.ip().is_unspecified() {
            wake.set_ip(match wake {
                SocketAddr::V4(_) => Ipv4Addr::LOCALHOST.into(),
                SocketAddr::V6(_) => Ipv6Addr::LOCALHOST.into(),
            });
        }
        if TcpStream::connect_timeout(&wake, Duration::from_secs(1)).is_ok() {
            let _ = self.accepting.join();
        }
        let open = std::mem::take(&mut *self.open.lock().unwrap_or_else(|e| e.into_inner()));
        for end in open.values().flatten() {
            let _ = end.shutdown(Shutdown::Both);
        }
    }
}

/// The accepting thread: a thread per connection, until the door closes.
fn accept(listener: &TcpListener, server: SocketAddr, closing: &AtomicBool, open: &Arc<Open>) {
    let numbers = AtomicU64::new(0);
    for client in listener.incoming() {
        if closing.load(Ordering::SeqCst) {
            return;
        }
        let Ok(client) = client else { continue };
        let number = numbers.fetch_add(1, Ordering::Relaxed);
        let open = open.clone();
        let _ = std::thread::Builder::new()
            .name("live view viewer".into())
            .spawn(move || {
                let _ = pass(client, server, number, &open);
                open.lock()
                    .unwrap_or_else(|e| e.into_inner())
                    .remove(&number);
            });
    }
}

/// One connection: the handshake, renamed if need be, then bytes both ways until either
/// side ends.
fn pass(mut client: TcpStream, server: SocketAddr, number: u64, open: &Open) -> io::Result<()> {
    client.set_read_timeout(Some(HEAD_TIMEOUT))?;
    let (request, early) = read_head(&mut client)?;
    client.set_read_timeout(None)?;
    let (request, renamed) = match rename_request(&request) {
        Some(r) => (r, true),
        None => (request, false),
    };
    let mut upstream = TcpStream::connect(server)?;
    let _ = upstream.set_nodelay(true);
    let _ = client.set_nodelay(true);
    upstream.write_all(&request)?;
    upstream.write_all(&early)?;
    let (response, early) = read_head(&mut upstream)?;
    let response = match renamed {
        true => rename_response(&response).unwrap_or(response),
        false => response,
    };
    client.write_all(&response)?;
    client.write_all(&early)?;
    open.lock()
        .unwrap_or_else(|e| e.into_inner())
        .insert(number, [client.try_clone()?, upstream.try_clone()?]);
    let down = {
        let (from, to) = (upstream.try_clone()?, client.try_clone()?);
        std::thread::Builder::new()
            .name("live view viewer".into())
            .spawn(move || copy(from, to))?
    };
    copy(client, upstream);
    let _ = down.join();
    Ok(())
}

/// Copies `from` to `to` until `from` ends (then ends `to`'s writing) or either fails
/// (then ends both).
fn copy(mut from: TcpStream, mut to: TcpStream) {
    match io::copy(&mut from, &mut to) {
        Ok(_) => {
            let _ = to.shutdown(Shutdown::Write);
        }
        Err(_) => {
            let _ = from.shutdown(Shutdown::Both);
            let _ = to.shutdown(Shutdown::Both);
        }
    }
}

/// An HTTP head (through its blank line) from `stream`, and the bytes read after it.
fn read_head(stream: &mut TcpStream) -> io::Result<(Vec<u8>, Vec<u8>)> {
    let mut buf = Vec::with_capacity(1024);
    let mut chunk = [0u8; 4096];
    loop {
        let n = stream.read(&mut chunk)?;
        if n == 0 {
            return Err(io::ErrorKind::UnexpectedEof.into());
        }
        let searched = buf.len().saturating_sub(3);
        buf.extend_from_slice(&chunk[..n]);
        if let Some(i) = buf[searched..].windows(4).position(|w| w == b"\r\n\r\n") {
            let end = searched + i + 4;
            let rest = buf.split_off(end);
            return Ok((buf, rest));
        }
        if buf.len() > HEAD_LIMIT {
            return Err(io::ErrorKind::InvalidData.into());
        }
    }
}

/// The head's lines and, per line, the value of a `Sec-WebSocket-Protocol` header; `None`
/// for a head that is not text.
fn lines(head: &[u8]) -> Option<Vec<(&str, Option<&str>)>> {
    let text = std::str::from_utf8(head).ok()?;
    let text = text.strip_suffix("\r\n\r\n")?;
    Some(
        text.split("\r\n")
            .map(|line| {
                let value = line
                    .split_once(':')
                    .filter(|(name, _)| name.trim().eq_ignore_ascii_case(HEADER))
                    .map(|(_, value)| value.trim());
                (line, value)
            })
            .collect(),
    )
}

/// The lines joined back into a head.
fn join(lines: impl IntoIterator<Item = String>) -> Vec<u8> {
    let mut head: String = lines.into_iter().map(|l| l + "\r\n").collect();
    head.push_str("\r\n");
    head.into_bytes()
}

/// The request with the new name in place of the old, if it offers the old name and none
/// of the new ones; `None`: it passes as it is.
pub fn rename_request(head: &[u8]) -> Option<Vec<u8>> {
    let lines = lines(head)?;
    let offered: Vec<&str> = lines
        .iter()
        .filter_map(|(_, v)| *v)
        .flat_map(|v| v.split(','))
        .map(str::trim)
        .collect();
    if !offered.contains(&SPEC_NAME) || offered.iter().any(|o| SDK_NAMES.contains(o)) {
        return None;
    }
    let mut renamed = false;
    Some(join(lines.into_iter().filter_map(|(line, value)| {
        match (value, renamed) {
            (None, _) => Some(line.to_owned()),
            (Some(_), true) => None,
            (Some(_), false) => {
                renamed = true;
                Some(format!("Sec-WebSocket-Protocol: {}", SDK_NAMES[0]))
            }
        }
    })))
}

/// The server's answer with the old name in place of the new one it chose; `None`: it
/// chose none (a refusal).
pub fn rename_response(head: &[u8]) -> Option<Vec<u8>> {
    let lines = lines(head)?;
    lines.iter().find(|(_, v)| *v == Some(SDK_NAMES[0]))?;
    Some(join(lines.into_iter().map(|(line, value)| match value {
        Some(_) => format!("Sec-WebSocket-Protocol: {SPEC_NAME}"),
        None => line.to_owned(),
    })))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn request(protocols: &[&str]) -> Vec<u8> {
        let mut lines = vec![
            "GET / HTTP/1.1".to_owned(),
            "Host: 127.0.0.1:8765".to_owned(),
            "Upgrade: websocket".to_owned(),
        ];
        lines.extend(
            protocols
                .iter()
                .map(|p| format!("sec-websocket-protocol: {p}")),
        );
        lines.push("Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==".to_owned());
        join(lines)
    }

    #[test]
    fn the_old_name_alone_is_renamed_once() {
        for offered in [
            vec![SPEC_NAME],
            vec!["other, foxglove.websocket.v1"],
            vec!["other", " foxglove.websocket.v1 "],
        ] {
            let renamed = rename_request(&request(&offered)).expect("renamed");
            assert_eq!(
                String::from_utf8(renamed).unwrap(),
                "GET / HTTP/1.1\r\nHost: 127.0.0.1:8765\r\nUpgrade: websocket\r\n\
                 Sec-WebSocket-Protocol: foxglove.sdk.v1\r\n\
                 Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n\r\n",
                "{offered:?}"
            );
        }
    }

    #[test]
    fn an_offer_the_server_accepts_or_refuses_passes_as_it_is() {
        for offered in [
            vec!["foxglove.sdk.v1"],
            vec!["foxglove.websocket.v1, foxglove.sdk.v1"],
            vec!["foxglove.websocket.v1", "foxglove.sdk.v1.1"],
            vec!["foxglove.websocket.v10"],
            vec![],
        ] {
            assert_eq!(rename_request(&request(&offered)), None, "{offered:?}");
        }
        assert_eq!(rename_request(b"GET / HTTP/1.1\r\n\xff\r\n\r\n"), None);
    }

    #[test]
    fn the_servers_choice_is_renamed_back() {
        let ok = b"HTTP/1.1 101 Switching Protocols\r\nConnection: Upgrade\r\n\
                   sec-websocket-protocol: foxglove.sdk.v1\r\n\r\n";
        assert_eq!(
            String::from_utf8(rename_response(ok).unwrap()).unwrap(),
            "HTTP/1.1 101 Switching Protocols\r\nConnection: Upgrade\r\n\
             Sec-WebSocket-Protocol: foxglove.websocket.v1\r\n\r\n"
        );
        let refused = b"HTTP/1.1 400 Bad Request\r\ncontent-length: 0\r\n\r\n";
        assert_eq!(rename_response(refused), None);
    }
}
