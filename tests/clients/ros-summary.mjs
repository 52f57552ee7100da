// What the test clients print of a decoded ROS 2 message, shared by the MCAP reader
// (mcap-read.mjs) and the Foxglove WebSocket client (foxglove-view.mjs): images as a FNV-1a hash
// of their pixels and samples on a grid of GRID x GRID points, clouds as their points, the rest as
// their fields. The tests compare these with the pipeline's own results.
import { parse } from "@foxglove/rosmsg";
import { MessageReader } from "@foxglove/rosmsg2-serialization";

// A decoder of the messages of a `ros2msg` schema.
export function decoderOf(schemaText) {
  return new MessageReader(parse(schemaText, { ros2: true }));
}

let grid = 8;
export function setGrid(n) {
  grid = n;
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

export function summary(type, m) {
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
    case "foxglove_msgs/msg/ImageAnnotations":
      return { circles: m.circles.length,
        boxes: m.points.map((p) => ({ type: p.type, thickness: p.thickness,
          points: p.points.map((q) => [q.x, q.y]) })),
        texts: m.texts.map((t) => ({ text: t.text, position: [t.position.x, t.position.y],
          font_size: t.font_size })) };
    default: throw new Error(`no summary for ${type}`);
  }
}

// The message as the tests read it: its topic, type and stamp, and its summary.
export function describe(topic, type, m, extra = {}) {
  const stamp = m.header?.stamp ?? m.transforms?.[0]?.header.stamp ?? m.points?.[0]?.timestamp;
  return { topic, type, ...extra, stamp: stamp ? [stamp.sec, stamp.nanosec ?? stamp.nsec] : null,
    ...summary(type, m) };
}
