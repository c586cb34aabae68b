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

/** A 2D inset drawing a section's fill and contours, fitted to the (u, v) box given. */
export function makeInset(colours) {
  const size = 220;
  const canvas = element('canvas',
    'position:absolute;right:8px;bottom:8px;background:rgba(255,255,255,.9);border-radius:6px;' +
    'box-shadow:0 1px 4px rgba(0,0,0,.2)');
  canvas.width = size;
  canvas.height = size;
  canvas.style.display = 'none';
  document.body.append(canvas);
  const ctx = canvas.getContext('2d');
  return {
    draw(section, box) {
      if (!section) {
        canvas.style.display = 'none';
        return;
      }
      canvas.style.display = 'block';
      ctx.clearRect(0, 0, size, size);
      const pad = 10;
      const extent = Math.max(box[2] - box[0], box[3] - box[1]) || 1;
      const k = (size - 2 * pad) / extent;
      const x = (u) => pad + (u - box[0]) * k;
      const y = (v) => size - pad - (v - box[1]) * k;
      ctx.fillStyle = colours.section;
      ctx.beginPath();
      const f = section.fill;
      for (let t = 0; t < f.length; t += 6) {
        ctx.moveTo(x(f[t]), y(f[t + 1]));
        ctx.lineTo(x(f[t + 2]), y(f[t + 3]));
        ctx.lineTo(x(f[t + 4]), y(f[t + 5]));
        ctx.closePath();
      }
      ctx.fill();
      ctx.strokeStyle = '#222';
      ctx.lineWidth = 1;
      ctx.beginPath();
      const l = section.lines;
      for (let s = 0; s < l.length; s += 4) {
        ctx.moveTo(x(l[s]), y(l[s + 1]));
        ctx.lineTo(x(l[s + 2]), y(l[s + 3]));
      }
      ctx.stroke();
    },
  };
}
