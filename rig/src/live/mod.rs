//! The live view, `rig run --live [ADDR]`: the run's channels served over the Foxglove
//! WebSocket protocol (the official `foxglove` crate's server) as they are recorded.
//! Viewers connect through a [`Door`] that lets in clients offering either of the
//! protocol's names ([`door`]).
//!
//! The recorder hands every channel and message to a [`Feed`] ([`runtime::record::Tap`]),
//! in the recording's own encodings and schemas, so that one layout serves the recording
//! and the live view: the loop's channels, `/returns`, `/latency` and `/scene`, the
//! system's picture (`crate::picture`). The feed copies a message only when a viewer
//! subscribes to its channel ([`watched`]: a run served to nobody costs next to nothing),
//! into a bounded queue, and returns: when the queue is full (the view's thread is behind)
//! the message is dropped and counted, never waited for, so the loop never waits for a
//! viewer. The view's thread logs each message on its Foxglove channel — of `/scene` at
//! most [`PICTURES_PER_SECOND`] a second, the latest —; the server's queue per client (of
//! [`BACKLOG`] messages) drops its oldest when a viewer reads too slowly.

use std::net::{Ipv4Addr, SocketAddr};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError, SyncSender, TrySendError, sync_channel};
use std::thread::JoinHandle;
use std::time::Duration;

use anyhow::{Context as _, Result, anyhow};
use foxglove::{
    ChannelBuilder, Context, PartialMetadata, RawChannel, Schema, WebSocketServer,
    WebSocketServerHandle,
};
use runtime::record::Tap;
use runtime::record::channels::SCENE;
use runtime::record::scene::Encoding;

pub mod door;
pub mod pace;
pub mod watched;

use door::Door;
use pace::Pace;
use watched::{REFRESH, Watched};
use wire::Monotonic;

/// The messages waiting between the recorder and the view's thread; beyond them, a
/// message is dropped.
pub const QUEUE: usize = 4096;
/// The messages the server holds per viewer; beyond them, it drops the oldest.
pub const BACKLOG: usize = 4096;
/// How often at most the system is drawn, per second of wall-clock time.
pub const PICTURES_PER_SECOND: u32 = 30;
/// How long the server stays up after the run for its last messages to go out.
const LINGER: Duration = Duration::from_millis(300);
/// How long the server's stop may take at most.
const STOP: Duration = Duration::from_secs(2);

/// What the recorder hands on: a channel declared or a message.
enum Event {
    Channel {
        topic: String,
        encoding: Encoding,
    },
    Message {
        index: usize,
        log_time_ns: u64,
        data: Vec<u8>,
    },
}

/// The recorder's end of the live view: a [`Tap`] that never waits.
pub struct Feed {
    queue: SyncSender<Event>,
    dropped: Arc<AtomicU64>,
    watched: Arc<Watched>,
}

impl Tap for Feed {
    fn channel(&mut self, topic: &str, encoding: &Encoding) {
        // Channels are declared before the loop starts: waiting here holds nothing back.
        let _ = self.queue.send(Event::Channel {
            topic: topic.to_owned(),
            encoding: encoding.clone(),
        });
    }

    fn message(&mut self, index: usize, log_time_ns: u64, data: &[u8]) {
        if !self.watched.wants(index) {
            return;
        }
        let event = Event::Message {
            index,
            log_time_ns,
            data: data.to_vec(),
        };
        if let Err(TrySendError::Full(_)) = self.queue.try_send(event) {
            self.dropped.fetch_add(1, Ordering::Relaxed);
        }
    }
}

/// What the live view did, for the run's summary.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Served {
    /// Messages logged to the server: those of the channels a viewer subscribed to.
    pub messages: u64,
    /// Messages dropped because the view's thread was behind.
    pub dropped: u64,
    /// Pictures of the system served (of `/scene`, at most [`PICTURES_PER_SECOND`] a
    /// second).
    pub pictures: u64,
}

impl std::fmt::Display for Served {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "live view: {} messages served, {} dropped (the view behind the run), {} pictures of the system",
            self.messages, self.dropped, self.pictures
        )
    }
}

/// The server and the thread that feeds it.
pub struct LiveView {
    server: WebSocketServerHandle,
    door: Door,
    thread: JoinHandle<Served>,
    dropped: Arc<AtomicU64>,
}

impl LiveView {
    /// Starts the server on `addr` for a run of `task`; returns it and the feed to give
    /// the recorder ([`runtime::run::run_with`]).
    pub fn start(addr: SocketAddr, task: &plant::Task) -> Result<(LiveView, Box<dyn Tap>)> {
        let refused =
            |e: &dyn std::fmt::Display| anyhow!("--live {addr}: cannot serve the live view: {e}");
        let ctx = Context::new();
        // The server on this host only, behind the door where the user asked.
        let server = WebSocketServer::new()
            .name(format!("rig {}", task.name))
            .bind(Ipv4Addr::LOCALHOST.to_string(), 0)
            .message_backlog_size(BACKLOG)
            .context(&ctx)
            .start_blocking()
            .map_err(|e| refused(&e))?;
        let inside = SocketAddr::new(Ipv4Addr::LOCALHOST.into(), server.port());
        let door = match Door::open(addr, inside) {
            Ok(door) => door,
            Err(e) => {
                let _ = server.stop();
                return Err(refused(&e));
            }
        };
        let (queue, events) = sync_channel(QUEUE);
        let dropped = Arc::new(AtomicU64::new(0));
        let watched = Arc::new(Watched::default());
        let view = View::new(ctx, watched.clone(), Monotonic::host());
        let thread = std::thread::Builder::new()
            .name("live view".into())
            .spawn(move || view.serve(&events))
            .context("cannot start the live view's thread")?;
        let feed = Feed {
            queue,
            dropped: dropped.clone(),
            watched,
        };
        let live = LiveView {
            server,
            door,
            thread,
            dropped,
        };
        Ok((live, Box::new(feed)))
    }

    /// Where it listens.
    pub fn addr(&self) -> SocketAddr {
        self.door.addr()
    }

    /// After the run (the feed dropped with the recorder): serves what is left, stops the
    /// server and says what it did.
    pub fn close(self) -> Served {
        let mut served = self.thread.join().unwrap_or_default();
        served.dropped = self.dropped.load(Ordering::Relaxed);
        if self.server.client_count() > 0 {
            std::thread::sleep(LINGER);
        }
        // A viewer that stopped reading may never close: wait for so long only.
        let stopping = self.server.stop();
        let (stopped, wait) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            stopping.wait_blocking();
            let _ = stopped.send(());
        });
        let _ = wait.recv_timeout(STOP);
        self.door.close();
        served
    }
}

/// The view's thread: the channels, and the latest picture of the system.
struct View {
    ctx: Arc<Context>,
    channels: Vec<Arc<RawChannel>>,
    /// The channel of the system's pictures, `/scene`.
    scene: Option<usize>,
    /// The latest picture not served yet: its log time and message.
    latest: Option<(u64, Vec<u8>)>,
    /// The pictures' pace: [`PICTURES_PER_SECOND`].
    pictures: Pace,
    /// The subscriptions' pace: every [`REFRESH`].
    refreshes: Pace,
    served: Served,
    /// The feed's flags, set from the server's subscriptions.
    watched: Arc<Watched>,
}

impl View {
    /// The view of the channels of `ctx`, their flags in `watched`, paced on `time`.
    fn new(ctx: Arc<Context>, watched: Arc<Watched>, time: Monotonic) -> View {
        let pictures = Duration::from_secs(1) / PICTURES_PER_SECOND;
        View {
            ctx,
            channels: Vec::new(),
            scene: None,
            latest: None,
            pictures: Pace::every(pictures, time.clone()),
            refreshes: Pace::every(REFRESH, time),
            served: Served::default(),
            watched,
        }
    }

    fn serve(mut self, events: &Receiver<Event>) -> Served {
        self.refreshes.went();
        loop {
            if self.refreshes.due() {
                self.refresh();
                self.refreshes.went();
            }
            let event = match events.recv_timeout(REFRESH) {
                Ok(event) => event,
                Err(RecvTimeoutError::Timeout) => continue,
                Err(RecvTimeoutError::Disconnected) => break,
            };
            match event {
                Event::Channel { topic, encoding } => self.channel(&topic, encoding),
                Event::Message {
                    index,
                    log_time_ns,
                    data,
                } => self.message(index, log_time_ns, data),
            }
        }
        self.show();
        self.served
    }

    fn channel(&mut self, topic: &str, e: Encoding) {
        if topic == SCENE {
            self.scene = Some(self.channels.len());
        }
        let schema = Schema::new(e.schema_name, e.schema_encoding, e.schema);
        let channel = ChannelBuilder::new(topic)
            .message_encoding(e.message_encoding)
            .schema(schema)
            .context(&self.ctx)
            .build_raw()
            .expect("a topic is declared once");
        self.channels.push(channel);
        self.refresh();
    }

    /// Sets the feed's flags from the server's subscriptions: a channel is wanted when a
    /// viewer subscribes to it.
    fn refresh(&self) {
        for (i, channel) in self.channels.iter().enumerate() {
            self.watched.set(i, channel.has_sinks());
        }
    }

    fn message(&mut self, index: usize, log_time_ns: u64, data: Vec<u8>) {
        if self.scene == Some(index) {
            self.latest = Some((log_time_ns, data));
            if self.pictures.due() {
                self.show();
            }
            return;
        }
        let Some(channel) = self.channels.get(index) else {
            return;
        };
        channel.log_with_meta(&data, PartialMetadata::with_log_time(log_time_ns));
        self.served.messages += 1;
    }

    /// Serves the latest picture, if any is new.
    fn show(&mut self) {
        let (Some((log_time_ns, data)), Some(i)) = (self.latest.take(), self.scene) else {
            return;
        };
        self.channels[i].log_with_meta(&data, PartialMetadata::with_log_time(log_time_ns));
        self.served.messages += 1;
        self.served.pictures += 1;
        self.pictures.went();
    }
}
