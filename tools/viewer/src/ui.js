// The page's controls: axis, on/off, slider and the height and area read-out.

function element(tag, style, text) {
  const e = document.createElement(tag);
  if (style) e.style.cssText = style;
  if (text) e.textContent = text;
  return e;
}

/** The control panel; `onChange({ on, axis, fraction })` is called on every change. */
export function makePanel(title, triangles, onChange) {
  const panel = element('div',
    'position:absolute;top:8px;left:8px;padding:8px 10px;background:rgba(255,255,255,.85);' +
    'border-radius:6px;box-shadow:0 1px 4px rgba(0,0,0,.2);color:#222;min-width:240px');
  panel.append(element('div', 'font-weight:600', title));
  panel.append(element('div', 'color:#555', `${triangles.toLocaleString('en')} triangles`));
  const row = element('div', 'margin-top:6px');
  const on = element('input');
  on.type = 'checkbox';
  on.id = 'pgvol-section-on';
  const label = element('label', 'margin:0 6px 0 2px', 'section');
  label.htmlFor = on.id;
  const axis = element('select');
  for (const name of ['x', 'y', 'z']) {
    const o = element('option', null, name);
    o.value = name;
    axis.append(o);
  }
  axis.value = 'z';
  row.append(on, label, axis);
  const slider = element('input', 'width:100%;display:block;margin-top:4px');
  slider.type = 'range';
  slider.min = '0';
  slider.max = '1000';
  slider.value = '500';
  const readout = element('div', 'font-variant-numeric:tabular-nums;color:#333');
  panel.append(row, slider, readout);
  document.body.append(panel);
  const fire = () => onChange({
    on: on.checked,
    axis: 'xyz'.indexOf(axis.value),
    fraction: Number(slider.value) / 1000,
  });
  on.addEventListener('change', fire);
  axis.addEventListener('change', fire);
  slider.addEventListener('input', fire);
  return {
    set(state) {
      on.checked = state.on;
      axis.value = 'xyz'[state.axis];
      slider.value = String(Math.round(state.fraction * 1000));
    },
    show(text) {
      readout.textContent = text;
    },
  };
}

/** The colour `#rrggbb` as [r, g, b]. */
function rgb(hex) {
  const n = parseInt(hex.slice(1), 16);
  return [(n >> 16) & 255, (n >> 8) & 255, n & 255];
}

/**
 * A 2D inset showing a section: each pixel takes the plane's values interpolated bilinearly
 * (as the contour's edges are), filled where below the level, dark where the sign changes
 * between neighbouring pixels. Drawn pixel by pixel, so its cost is the inset's size whatever
 * the section holds.
 */
export function makeInset(colours) {
  const size = 220;
  const pad = 10;
  const canvas = element('canvas',
    'position:absolute;right:8px;bottom:8px;background:rgba(255,255,255,.9);border-radius:6px;' +
    'box-shadow:0 1px 4px rgba(0,0,0,.2)');
  canvas.width = size;
  canvas.height = size;
  canvas.style.display = 'none';
  document.body.append(canvas);
  const ctx = canvas.getContext('2d');
  const fill = rgb(colours.section);
  return {
    /** Draws `plane` (from BrickField.plane) below `iso` over the (u, v) box, or hides. */
    draw(plane, iso, box) {
      if (!plane) {
        canvas.style.display = 'none';
        return;
      }
      canvas.style.display = 'block';
      const { values, nu, nv, origin, spacing } = plane;
      const extent = Math.max(box[2] - box[0], box[3] - box[1]) || 1;
      const step = extent / (size - 2 * pad);
      const inside = new Uint8Array(size * size);
      for (let y = 0; y < size; y++) {
        const gv = (box[1] + (size - 1 - y - pad + 0.5) * step - origin[1]) / spacing;
        if (gv < 0 || gv > nv - 1) continue;
        const j = Math.min(Math.floor(gv), nv - 2);
        const tv = gv - j;
        for (let x = 0; x < size; x++) {
          const gu = (box[0] + (x - pad + 0.5) * step - origin[0]) / spacing;
          if (gu < 0 || gu > nu - 1) continue;
          const i = Math.min(Math.floor(gu), nu - 2);
          const tu = gu - i;
          const k = i + nu * j;
          const low = values[k] * (1 - tu) + values[k + 1] * tu;
          const high = values[k + nu] * (1 - tu) + values[k + nu + 1] * tu;
          inside[x + size * y] = low * (1 - tv) + high * tv < iso ? 1 : 0;
        }
      }
      const image = ctx.createImageData(size, size);
      const px = image.data;
      for (let y = 0; y < size; y++) {
        for (let x = 0; x < size; x++) {
          const p = x + size * y;
          const edge = (x + 1 < size && inside[p + 1] !== inside[p]) ||
            (y + 1 < size && inside[p + size] !== inside[p]);
          const c = edge ? [34, 34, 34] : inside[p] ? fill : null;
          if (!c) continue;
          px[4 * p] = c[0];
          px[4 * p + 1] = c[1];
          px[4 * p + 2] = c[2];
          px[4 * p + 3] = 255;
        }
      }
      ctx.clearRect(0, 0, size, size);
      ctx.putImageData(image, 0, 0);
    },
  };
}
