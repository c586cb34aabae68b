// `#section=z:H` in the page's address: the section to show, overriding the one written in.

/** The section of an address fragment, as { axis: 0|1|2, height }, or null. */
export function sectionOfHash(hash) {
  const m = /(?:^#|&)section=([xyz]):([-+0-9.eE]+)/.exec(hash || '');
  if (!m) return null;
  const height = Number(m[2]);
  if (!Number.isFinite(height)) return null;
  return { axis: 'xyz'.indexOf(m[1]), height };
}
