// The field on an axis-aligned plane, from the node values of a sparse brick grid: along the
// plane's axis the basis is evaluated at the plane's height, across the plane at the nodes,
// where the cubic B-spline's taps are 1/6, 4/6, 1/6 (the linear one's is 1).

import { bytesOf } from './data.js';

const EDGE = 8;
const BRICK = EDGE * EDGE * EDGE;
const OUTSIDE = 0;
const INSIDE = 1;

/** The (axis, u, v) indices of a section along `axis` (0 x, 1 y, 2 z), as pgvol slice uses. */
export function planeAxes(axis) {
  return [[0, 1, 2], [1, 2, 0], [2, 0, 1]][axis];
}

/** Index `i` reflected about the end nodes of an axis of `n` nodes (whole-sample symmetry). */
function mirror(i, n) {
  const m = i < 0 ? -i : i >= n ? 2 * (n - 1) - i : i;
  return Math.min(Math.max(m, 0), n - 1);
}

/** The centred cubic B-spline at `x`. */
function cubic(x) {
  const a = Math.abs(x);
  if (a < 1) return (4 - 6 * a * a + 3 * a * a * a) / 6;
  if (a < 2) return ((2 - a) ** 3) / 6;
  return 0;
}

export class BrickField {
  constructor(field) {
    this.basis = field.basis;
    this.origin = field.origin;
    this.spacing = field.spacing;
    this.dims = field.dims;
    this.bricks = field.bricks;
    this.scale = field.scale;
    this.inside = field.inside;
    this.outside = field.outside;
    const states = bytesOf(field.states);
    this.slots = new Int32Array(states.length);
    let next = 0;
    for (let b = 0; b < states.length; b++) {
      const s = states[b];
      this.slots[b] = s === OUTSIDE ? -1 : s === INSIDE ? -2 : next++;
    }
    this.values = new Int16Array(bytesOf(field.values).buffer);
    if (this.values.length !== next * BRICK) {
      throw new Error(`the field holds ${this.values.length} values for ${next} bricks`);
    }
  }

  /** The node value at indices (i, j, k) inside the grid. */
  node(i, j, k) {
    const [bx, by] = this.bricks;
    const slot = this.slots[(i >> 3) + bx * ((j >> 3) + by * (k >> 3))];
    if (slot === -1) return this.outside;
    if (slot === -2) return this.inside;
    return this.values[slot * BRICK + (i & 7) + ((j & 7) << 3) + ((k & 7) << 6)] * this.scale;
  }

  /** Node span of the grid along `axis`, in local coordinates. */
  range(axis) {
    const lo = this.origin[axis];
    return [lo, lo + (this.dims[axis] - 1) * this.spacing];
  }

  /** First node index and weights of the basis along an axis of `n` nodes at grid coordinate u. */
  taps(u, n) {
    const c = Math.min(Math.max(Math.floor(u), 0), n - 2);
    if (this.basis === 'trilinear') {
      const t = Math.min(Math.max(u - c, 0), 1);
      return { first: c, weights: [1 - t, t] };
    }
    const first = c - 1;
    return { first, weights: [0, 1, 2, 3].map((m) => cubic(u - first - m)) };
  }

  /**
   * Field values at the nodes of the plane at local `height` along `axis`: a Float32Array of
   * nu × nv (u fastest), with the plane's lattice; null when the plane misses the grid.
   */
  plane(axis, height) {
    const [a, ua, va] = planeAxes(axis);
    const [lo, hi] = this.range(a);
    if (!(height >= lo && height <= hi)) return null;
    const n = this.dims;
    const { first, weights } = this.taps((height - lo) / this.spacing, n[a]);
    const nu = n[ua];
    const nv = n[va];
    const idx = [0, 0, 0];
    // Collapse along the axis: one value per (u, v) node.
    const collapsed = new Float32Array(nu * nv);
    for (let m = 0; m < weights.length; m++) {
      const w = weights[m];
      if (w === 0) continue;
      idx[a] = mirror(first + m, n[a]);
      for (let j = 0; j < nv; j++) {
        idx[va] = j;
        for (let i = 0; i < nu; i++) {
          idx[ua] = i;
          collapsed[i + nu * j] += w * this.node(idx[0], idx[1], idx[2]);
        }
      }
    }
    let values = collapsed;
    if (this.basis !== 'trilinear') values = nodeTaps(nodeTaps(collapsed, nu, nv, 1, nu), nv, nu, nu, 1);
    return {
      values,
      nu,
      nv,
      origin: [this.origin[ua], this.origin[va]],
      spacing: this.spacing,
      axes: [a, ua, va],
    };
  }
}

/**
 * The cubic B-spline's node taps (1/6, 4/6, 1/6) along one direction of a 2D array: `len`
 * nodes along it at `stride`, `count` lines at `step`, mirrored at the ends.
 */
function nodeTaps(src, len, count, stride, step) {
  const out = new Float32Array(src.length);
  for (let line = 0; line < count; line++) {
    const base = line * step;
    for (let i = 0; i < len; i++) {
      const before = src[base + mirror(i - 1, len) * stride];
      const after = src[base + mirror(i + 1, len) * stride];
      out[base + i * stride] = (before + 4 * src[base + i * stride] + after) / 6;
    }
  }
  return out;
}
