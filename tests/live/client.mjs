// A viewer of `rig run --live` with the official Foxglove WebSocket protocol client:
// connects (retrying until the server is up), subscribes to every channel, decodes each
// JSON message and writes, one line per message, what it received — the topic, the log
// time, the message's text and its decoded value — to --out when the server
// closes. Messages of other encodings (the protobuf /scene) are counted with their schema.
//
//   node tests/live/client.mjs --url ws://127.0.0.1:8765 --out received.jsonl \
//        [--offer spec|sdk|both] [--stall]
//
// --offer: the subprotocol names the client offers — the client's own,
// `foxglove.websocket.v1` (spec, the default: FoxgloveClient.SUPPORTED_SUBPROTOCOL), the
// Foxglove SDK's name for the same protocol, `foxglove.sdk.v1` (sdk), or both, as current
// Foxglove and Lichtblick releases do. The client exits with an error if the server
// chose a name it did not offer.
//
// --stall: subscribe, then stop reading the socket (a viewer that hangs), until the
// server closes; for measuring what such a viewer costs the loop.
import { writeFileSync } from "node:fs";
import { connect as tcpConnect } from "node:net";
import { parseArgs } from "node:util";
import protocol from "@foxglove/ws-protocol";
import { WebSocket } from "ws";

const { FoxgloveClient } = protocol;
const SDK_SUBPROTOCOL = "foxglove.sdk.v1";
const OFFERS = {
  spec: [FoxgloveClient.SUPPORTED_SUBPROTOCOL],
  sdk: [SDK_SUBPROTOCOL],
  both: [FoxgloveClient.SUPPORTED_SUBPROTOCOL, SDK_SUBPROTOCOL],
};

const { values: args } = parseArgs({
  options: {
    url: { type: "string", default: "ws://127.0.0.1:8765" },
    out: { type: "string" },
    stall: { type: "boolean", default: false },
    offer: { type: "string", default: "spec" },
    "connect-seconds": { type: "string", default: "20" },
  },
});
const deadline = Date.now() + 1000 * Number(args["connect-seconds"]);
const offered = OFFERS[args.offer];
if (!offered) {
  console.error(`client: --offer ${args.offer}: one of ${Object.keys(OFFERS).join(", ")}`);
  process.exit(2);
}

function connect() {
  const ws = new WebSocket(args.url, offered);
  ws.on("error", () => {}); // retried below, or reported by the client
  ws.once("unexpected-response", (_request, response) => {
    console.error(`client: ${args.url} refused ${offered}: HTTP ${response.statusCode}`);
    process.exit(1);
  });
  ws.once("close", () => {
    if (!opened) {
      if (Date.now() > deadline) {
        console.error(`client: no server at ${args.url}`);
        process.exit(1);
      }
      setTimeout(connect, 50);
    }
  });
  ws.once("open", () => {
    opened = true;
    if (!offered.includes(ws.protocol)) {
      console.error(`client: the server chose ${ws.protocol}, not one of ${offered}`);
      process.exit(1);
    }
    view(ws);
  });
}

let opened = false;
connect();

function view(ws) {
  const client = new FoxgloveClient({ ws });
  const subscriptions = new Map();
  const lines = [];
  const others = {};
  const decoder = new TextDecoder();
  client.on("advertise", (channels) => {
    for (const channel of channels) {
      const id = client.subscribe(channel.id);
      subscriptions.set(id, channel);
    }
    if (args.stall && !stalled) {
      // Subscribed: now read nothing more. The server's queue for this viewer fills; the
      // client ends when the server no longer accepts connections.
      stalled = true;
      setTimeout(() => ws._socket.pause(), 100);
      setInterval(() => {
        const probe = tcpConnect(new URL(args.url).port, new URL(args.url).hostname);
        probe.on("connect", () => probe.destroy());
        probe.on("error", () => done());
      }, 200);
    }
  });
  client.on("message", ({ subscriptionId, timestamp, data }) => {
    const channel = subscriptions.get(subscriptionId);
    const bytes = new Uint8Array(data.buffer, data.byteOffset, data.byteLength);
    if (channel.encoding !== "json") {
      const key = `${channel.topic} ${channel.encoding} ${channel.schemaName}`;
      others[key] = (others[key] ?? 0) + 1;
      return;
    }
    const text = decoder.decode(bytes);
    lines.push(
      JSON.stringify({
        topic: channel.topic,
        log_time: timestamp.toString(),
        raw: text,
        value: JSON.parse(text),
      }),
    );
  });
  let stalled = false;
  const done = () => {
    if (args.out) {
      const counts = JSON.stringify({ others, protocol: ws.protocol });
      writeFileSync(args.out, [counts, ...lines].join("\n") + "\n");
    }
    console.error(`client: ${lines.length} JSON messages, others ${JSON.stringify(others)}`);
    process.exit(0);
  };
  client.on("close", done);
}
