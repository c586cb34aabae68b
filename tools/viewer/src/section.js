// Marching squares on a plane of node values: each cell's inside (value below the level) as
// a polygon clipped along the linearly interpolated level, filled as a fan of triangles; the
// section's area is the sum of the polygons' areas.

/**
 * The inside of `plane` (from BrickField.plane) below `iso`: fill triangles and contour
 * segments as flat arrays of (u, v) pairs in local coordinates, and the area.
 */
export function contour(plane, iso) {
  const { values, nu, nv, origin, spacing } = plane;
  const fill = [];
  const lines = [];
  let area = 0;
  const cu = [0, 1, 1, 0];
  const cv = [0, 0, 1, 1];
  const poly = new Float64Array(16);
  const crossing = new Uint8Array(8);
  for (let j = 0; j + 1 < nv; j++) {
    for (let i = 0; i + 1 < nu; i++) {
      const f = [
        values[i + nu * j] - iso,
        values[i + 1 + nu * j] - iso,
        values[i + 1 + nu * (j + 1)] - iso,
        values[i + nu * (j + 1)] - iso,
      ];
      const inside = (f[0] < 0) + (f[1] < 0) + (f[2] < 0) + (f[3] < 0);
      if (inside === 0) continue;
      let count = 0;
      for (let e = 0; e < 4; e++) {
        const n = (e + 1) & 3;
        if (f[e] < 0) {
          poly[2 * count] = cu[e];
          poly[2 * count + 1] = cv[e];
          crossing[count++] = 0;
        }
        if (f[e] < 0 !== f[n] < 0) {
          const t = f[e] / (f[e] - f[n]);
          poly[2 * count] = cu[e] + t * (cu[n] - cu[e]);
          poly[2 * count + 1] = cv[e] + t * (cv[n] - cv[e]);
          crossing[count++] = 1;
        }
      }
      const u0 = origin[0] + i * spacing;
      const v0 = origin[1] + j * spacing;
      let twice = 0;
      for (let p = 0; p < count; p++) {
        const q = (p + 1) % count;
        twice += poly[2 * p] * poly[2 * q + 1] - poly[2 * q] * poly[2 * p + 1];
        if (crossing[p] && crossing[q]) {
          lines.push(
            u0 + poly[2 * p] * spacing, v0 + poly[2 * p + 1] * spacing,
            u0 + poly[2 * q] * spacing, v0 + poly[2 * q + 1] * spacing,
          );
        }
      }
      area += 0.5 * Math.abs(twice) * spacing * spacing;
      for (let p = 1; p + 1 < count; p++) {
        for (const s of [0, p, p + 1]) fill.push(u0 + poly[2 * s] * spacing, v0 + poly[2 * s + 1] * spacing);
      }
    }
  }
  return { fill, lines, area };
}
