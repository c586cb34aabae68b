// Reading the JSON the Rust side inlines (crates/pgvol/src/view/payload.rs): base64 blocks
// into typed arrays, the brick table into slots.

export const FORMAT = 1;

/** Bytes of a base64 string. */
export function bytesOf(text) {
  const raw = atob(text);
  const out = new Uint8Array(raw.length);
  for (let i = 0; i < raw.length; i++) out[i] = raw.charCodeAt(i);
  return out;
}

/** The payload of the page's data element, checked for its layout version. */
export function readPayload(doc) {
  const element = doc.getElementById('pgvol-data');
  if (!element) throw new Error('the page holds no field data');
  const data = JSON.parse(element.textContent);
  if (data.format !== FORMAT) {
    throw new Error(`page data of layout ${data.format}, this viewer reads ${FORMAT}`);
  }
  return data;
}

/** Positions (Float32Array, local frame) and indices of the inlined surface. */
export function surfaceArrays(surface) {
  const q = new Uint16Array(bytesOf(surface.positions).buffer);
  const positions = new Float32Array(q.length);
  for (let a = 0; a < 3; a++) {
    const lo = surface.lo[a];
    const step = (surface.hi[a] - surface.lo[a]) / 65535;
    for (let i = a; i < q.length; i += 3) positions[i] = lo + q[i] * step;
  }
  const raw = bytesOf(surface.indices).buffer;
  const indices = surface.index_bytes === 4 ? new Uint32Array(raw) : new Uint16Array(raw);
  return { positions, indices };
}
