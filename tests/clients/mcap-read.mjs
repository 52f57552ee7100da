// An independent reader of Epipole's MCAP recordings for the tests and the main job's check:
// reads FILE with the MCAP project's own TypeScript library (@mcap/core: the stream reader with
// every CRC checked, then the indexed reader through the summary and the chunk and message
// indexes), decodes every message with Foxglove's ROS 2 CDR decoder from the schema the file
// carries, and prints what it found as JSON: the header, the statistics, the attachments, and
// each message in log-time order with its decoded fields (pixel data as a FNV-1a hash and
// samples on a grid of GRID x GRID points).
//
//   node mcap-read.mjs FILE [GRID]
import { readFile } from "node:fs/promises";
import { McapIndexedReader, McapStreamReader } from "@mcap/core";
import { decompress } from "fzstd";
import { parse } from "@foxglove/rosmsg";
import { MessageReader } from "@foxglove/rosmsg2-serialization";

const [file, gridArg] = process.argv.slice(2);
if (!file) {
  console.error("usage: node mcap-read.mjs FILE [GRID]");
  process.exit(2);
}
const grid = Number(gridArg ?? 8);
const bytes = new Uint8Array(await readFile(file));
const decompressHandlers = {
  zstd: (data, size) => {
    const out = decompress(data, new Uint8Array(Number(size)));
    if (out.byteLength !== Number(size)) throw new Error("zstd: wrong decompressed size");
    return out;
  },
};

// 1. The stream reader: every record in file order, chunks CRC-checked.
const stream = new McapStreamReader({ decompressHandlers, validateCrcs: true });
stream.append(bytes);
const opcodes = {};
let streamMessages = 0;
for (let record; (record = stream.nextRecord()); ) {
  opcodes[record.type] = (opcodes[record.type] ?? 0) + 1;
  if (record.type === "Message") streamMessages++;
}
if (!stream.done()) throw new Error("the stream reader did not reach the end of the file");

// 2. The indexed reader: the summary, the chunk indexes and the message indexes.
const readable = {
  size: async () => BigInt(bytes.byteLength),
  read: async (offset, length) => bytes.subarray(Number(offset), Number(offset + length)),
};
const reader = await McapIndexedReader.Initialize({ readable, decompressHandlers });
const decoders = new Map();
for (const [id, channel] of reader.channelsById) {
  const schema = reader.schemasById.get(channel.schemaId);
  if (schema.encoding !== "ros2msg" || channel.messageEncoding !== "cdr") {
    throw new Error(`${channel.topic}: ${schema.encoding}/${channel.messageEncoding}`);
  }
  const definitions = parse(new TextDecoder().decode(schema.data), { ros2: true });
  decoders.set(id, { topic: channel.topic, type: schema.name, reader: new MessageReader(definitions) });
}

// FNV-1a over each row's pixels (width * bytes per pixel of each step).
function fnv1a(image, bytesPerPixel) {
  let h = 0x811c9dc5;
  for (let y = 0; y < image.height; y++) {
    const row = y * image.step;
    for (let i = 0; i < image.width * bytesPerPixel; i++) {
      h ^= image.data[row + i];
      h = Math.imul(h, 0x01000193) >>> 0;
    }
  }
  return h;
}
const bytesPerPixel = { mono8: 1, "16UC1": 2, "32FC1": 4 };

function pixelAt(image, x, y) {
  const view = new DataView(image.data.buffer, image.data.byteOffset, image.data.byteLength);
  const at = y * image.step;
  switch (image.encoding) {
    case "mono8": return image.data[at + x];
    case "16UC1": return view.getUint16(at + 2 * x, true);
    case "32FC1": return view.getFloat32(at + 4 * x, true);
    default: throw new Error(`encoding ${image.encoding}`);
  }
}

function imageSummary(image) {
  const samples = [];
  for (let j = 0; j < grid; j++) {
    for (let i = 0; i < grid; i++) {
      const x = Math.floor(((i + 0.5) * image.width) / grid);
      const y = Math.floor(((j + 0.5) * image.height) / grid);
      samples.push([x, y, pixelAt(image, x, y)]);
    }
  }
  if (image.data.length !== image.step * image.height) throw new Error("image data size");
  return {
    frame_id: image.header.frame_id, width: image.width, height: image.height,
    encoding: image.encoding, step: image.step, is_bigendian: image.is_bigendian,
    hash: fnv1a(image, bytesPerPixel[image.encoding]), samples,
  };
}

function cloudSummary(cloud) {
  const view = new DataView(cloud.data.buffer, cloud.data.byteOffset, cloud.data.byteLength);
  const offsets = Object.fromEntries(cloud.fields.map((f) => [f.name, f.offset]));
  const points = [];
  for (let i = 0; i < cloud.width * cloud.height; i++) {
    const at = i * cloud.point_step;
    points.push(["x", "y", "z", "intensity"].map((n) => view.getFloat32(at + offsets[n], true)));
  }
  return {
    frame_id: cloud.header.frame_id, width: cloud.width, height: cloud.height,
    fields: cloud.fields.map((f) => [f.name, f.offset, f.datatype, f.count]),
    point_step: cloud.point_step, row_step: cloud.row_step, is_dense: cloud.is_dense, points,
  };
}

function summary(type, m) {
  switch (type) {
    case "sensor_msgs/msg/Image": return imageSummary(m);
    case "sensor_msgs/msg/CameraInfo":
      return { frame_id: m.header.frame_id, width: m.width, height: m.height,
        distortion_model: m.distortion_model, d: Array.from(m.d), k: Array.from(m.k),
        r: Array.from(m.r), p: Array.from(m.p) };
    case "stereo_msgs/msg/DisparityImage":
      return { frame_id: m.header.frame_id, f: m.f, t: m.t, min_disparity: m.min_disparity,
        max_disparity: m.max_disparity, delta_d: m.delta_d, image: imageSummary(m.image) };
    case "sensor_msgs/msg/PointCloud2": return cloudSummary(m);
    case "tf2_msgs/msg/TFMessage":
      return { transforms: m.transforms.map((t) => ({ parent: t.header.frame_id,
        child: t.child_frame_id, translation: t.transform.translation,
        rotation: t.transform.rotation })) };
    case "diagnostic_msgs/msg/DiagnosticArray":
      return { status: m.status.map((s) => ({ level: s.level, name: s.name, message: s.message,
        hardware_id: s.hardware_id,
        values: Object.fromEntries(s.values.map((v) => [v.key, v.value])) })) };
    default: throw new Error(`no summary for ${type}`);
  }
}

const messages = [];
for await (const message of reader.readMessages({ validateCrcs: true })) {
  const decoder = decoders.get(message.channelId);
  const m = decoder.reader.readMessage(message.data);
  const stamp = m.header?.stamp ?? m.transforms?.[0]?.header.stamp;
  messages.push({ topic: decoder.topic, type: decoder.type, sequence: message.sequence,
    log_time: message.logTime.toString(),
    stamp: stamp ? [stamp.sec, stamp.nanosec ?? stamp.nsec] : null, ...summary(decoder.type, m) });
}
if (messages.length !== streamMessages) {
  throw new Error(`indexed reader: ${messages.length} messages, stream reader: ${streamMessages}`);
}
const attachments = [];
for await (const a of reader.readAttachments({ validateCrcs: true })) {
  attachments.push({ name: a.name, media_type: a.mediaType, text: new TextDecoder().decode(a.data) });
}
const statistics = reader.statistics;
console.log(JSON.stringify({
  profile: reader.header.profile, library: reader.header.library, records: opcodes,
  statistics: statistics && { message_count: Number(statistics.messageCount),
    chunk_count: statistics.chunkCount, channel_count: statistics.channelCount,
    channel_message_counts: Object.fromEntries([...statistics.channelMessageCounts].map(
      ([id, n]) => [reader.channelsById.get(id).topic, Number(n)])) },
  chunk_indexes: reader.chunkIndexes.length, attachments, messages,
}));
