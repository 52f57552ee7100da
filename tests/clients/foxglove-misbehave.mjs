// A client of Epipole's live view that does what it should not, for the tests: it connects
// without a Foxglove subprotocol, sends requests that are not JSON, ops the server does not
// serve, subscriptions to channels that do not exist or with ids in use, unsubscriptions of
// nothing and binary messages; then opens one connection more than the server's CLIENTS. It
// prints as JSON what came back: whether each connection was taken, the status messages, and
// whether a proper subscription still works afterwards.
//
//   node foxglove-misbehave.mjs URL CLIENTS
import WebSocket from "ws";

const [url, clientsArg] = process.argv.slice(2);
if (!url || !clientsArg) {
  console.error("usage: node foxglove-misbehave.mjs URL CLIENTS");
  process.exit(2);
}
const SUBPROTOCOL = "foxglove.websocket.v1";

// Opens a connection: resolves to the socket once the server's advertise came, or to null when
// the server refused it.
function connect(protocols) {
  return new Promise((resolve) => {
    const ws = new WebSocket(url, protocols);
    ws.statuses = [];
    ws.binary = [];
    ws.on("message", (data, isBinary) => {
      if (isBinary) {
        ws.binary.push(data);
        return;
      }
      const m = JSON.parse(data.toString());
      if (m.op === "advertise") {
        ws.channels = m.channels;
        resolve(ws);
      } else if (m.op === "status") {
        ws.statuses.push(m);
      }
    });
    ws.on("unexpected-response", () => resolve(null));
    ws.on("error", () => resolve(null));
    ws.on("close", () => resolve(null));
  });
}

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
const out = {};

out.without_subprotocol = (await connect(["not.foxglove"])) !== null;

const ws = await connect([SUBPROTOCOL]);
out.connected = ws !== null;
if (ws) {
  out.protocol = ws.protocol;
  const first = ws.channels[0].id;
  ws.send("this is not JSON");
  ws.send(JSON.stringify({ op: "setParameters", parameters: [] }));
  ws.send(JSON.stringify({ op: "subscribe", subscriptions: [{ id: 1, channelId: 999 }] }));
  ws.send(JSON.stringify({ op: "subscribe" }));
  ws.send(JSON.stringify({ op: "unsubscribe", subscriptionIds: [42] }));
  ws.send(Buffer.from([0x01, 0, 0, 0, 0, 1, 2, 3]), { binary: true });
  ws.send(JSON.stringify({ op: "subscribe", subscriptions: [{ id: 7, channelId: first }] }));
  ws.send(JSON.stringify({ op: "subscribe", subscriptions: [{ id: 7, channelId: first + 1 }] }));
  for (let i = 0; i < 100 && ws.binary.length === 0; i++) await sleep(50);
  out.statuses = ws.statuses.map((s) => ({ level: s.level, message: s.message }));
  out.messages_after = ws.binary.length;
  out.subscription_of_first = ws.binary.length > 0 ? ws.binary[0].readUInt32LE(1) : null;
  ws.send(JSON.stringify({ op: "unsubscribe", subscriptionIds: [7] }));
  await sleep(200);
  const before = ws.binary.length;
  await sleep(500);
  out.messages_after_unsubscribe = ws.binary.length - before;

  // The server's CLIENTS, this one among them, then one more.
  const others = [];
  for (let i = 1; i < Number(clientsArg); i++) others.push(await connect([SUBPROTOCOL]));
  out.others_connected = others.filter((o) => o !== null).length;
  out.one_too_many = (await connect([SUBPROTOCOL])) !== null;
  for (const o of others) o?.close();
  ws.close();
  await sleep(300);
  // The slots are free again.
  const again = await connect([SUBPROTOCOL]);
  out.after_closing = again !== null;
  again?.close();
}
process.stdout.write(JSON.stringify(out) + "\n", () => process.exit(0));
