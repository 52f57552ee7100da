// An independent client of Epipole's live view for the tests: Foxglove's own WebSocket protocol
// client (@foxglove/ws-protocol, over the `ws` package) connects to URL, subscribes to every
// channel the server advertises, decodes each message with Foxglove's ROS 2 CDR decoder from the
// schema the channel carries, and prints as JSON the server's info, its channels and each message
// (as mcap-read.mjs prints them) once every channel of the pairs has COUNT messages, /tf_static
// one and /diagnostics one. Exits 1, printing what it had, when that takes more than 60 s.
//
//   node foxglove-view.mjs URL COUNT [GRID] [--stall SECONDS]
//
// With --stall it subscribes, says "subscribed PID" on standard error, then stops reading for
// SECONDS (the socket paused: what the server sends piles up in the kernel's buffers), then
// reads again and goes on as above: a client that cannot keep up, for the server to drop
// messages to rather than wait for.
import WebSocket from "ws";
import foxglove from "@foxglove/ws-protocol";
import { decoderOf, describe, setGrid } from "./ros-summary.mjs";

const args = process.argv.slice(2);
const stallAt = args.indexOf("--stall");
const stallSeconds = stallAt >= 0 ? Number(args.splice(stallAt, 2)[1]) : 0;
const [url, countArg, gridArg] = args;
const { FoxgloveClient } = foxglove; // a CommonJS package
if (!url || !countArg) {
  console.error("usage: node foxglove-view.mjs URL COUNT [GRID] [--stall SECONDS]");
  process.exit(2);
}
const count = Number(countArg);
setGrid(Number(gridArg ?? 8));

const ws = new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]);
const client = new FoxgloveClient({ ws });
const out = { server_info: null, protocol: null, channels: [], messages: [] };
const channels = new Map(); // id: { topic, type, decoder }
const subscriptions = new Map(); // subscription id: channel id
const received = new Map(); // topic: messages decoded

// (Exits once the JSON is written: a pipe takes it in pieces.)
let finished = false;
function finish(code) {
  if (finished) return;
  finished = true;
  process.stdout.write(JSON.stringify(out) + "\n", () => process.exit(code));
}
const deadline = setTimeout(() => {
  out.error = "timed out";
  finish(1);
}, 60_000);

function complete() {
  for (const { topic } of channels.values()) {
    const n = received.get(topic) ?? 0;
    const needed = topic === "/tf_static" || topic === "/diagnostics" ? 1 : count;
    if (n < needed) return false;
  }
  return channels.size > 0;
}

client.on("open", () => {
  out.protocol = ws.protocol;
});
client.on("serverInfo", (info) => {
  out.server_info = info;
});
client.on("status", (status) => {
  (out.status ??= []).push(status);
});
client.on("error", (error) => {
  out.error = String(error);
  finish(1);
});
client.on("close", () => {
  out.error = "the server closed the connection";
  finish(1);
});
client.on("advertise", (advertised) => {
  for (const channel of advertised) {
    if (channel.encoding !== "cdr" || channel.schemaEncoding !== "ros2msg") {
      throw new Error(`${channel.topic}: ${channel.encoding}/${channel.schemaEncoding}`);
    }
    channels.set(channel.id, { topic: channel.topic, type: channel.schemaName,
      decoder: decoderOf(channel.schema) });
    out.channels.push({ id: channel.id, topic: channel.topic, type: channel.schemaName });
    subscriptions.set(client.subscribe(channel.id), channel.id);
  }
  if (stallSeconds > 0) {
    console.error(`subscribed ${process.pid}`);
    ws._socket.pause();
    setTimeout(() => ws._socket.resume(), stallSeconds * 1000);
  }
});
client.on("message", ({ subscriptionId, timestamp, data }) => {
  const channel = channels.get(subscriptions.get(subscriptionId));
  if (!channel) throw new Error(`a message of subscription ${subscriptionId}, never made`);
  const m = channel.decoder.readMessage(data);
  out.messages.push(describe(channel.topic, channel.type, m, { log_time: timestamp.toString() }));
  received.set(channel.topic, (received.get(channel.topic) ?? 0) + 1);
  if (complete()) {
    clearTimeout(deadline);
    client.close();
    finish(0);
  }
});
