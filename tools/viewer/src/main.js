// The viewer page: the inlined surface, lit, with orbit controls; one axis-aligned section
// computed from the field's node values, filled in the 3D view and in a 2D inset. The state
// tests read is set on <body>: data-status, data-triangles and, with a section shown,
// data-section-axis, data-section-height (model coordinates) and data-section-area; and
// data-ready-ms, the milliseconds from the start of navigation to the first frame drawn.

import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { readPayload, surfaceArrays } from './data.js';
import { BrickField, planeAxes } from './field.js';
import { contour } from './section.js';
import { sectionOfHash } from './hash.js';
import { makePanel, makeInset } from './ui.js';

function start() {
  const data = readPayload(document);
  const body = document.body;
  const colours = data.colours;
  const offset = data.offset;

  const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setSize(window.innerWidth, window.innerHeight);
  renderer.localClippingEnabled = true;
  renderer.setClearColor(new THREE.Color(colours.background));
  renderer.domElement.style.display = 'block';
  body.append(renderer.domElement);

  const scene = new THREE.Scene();
  const { positions, indices } = surfaceArrays(data.surface);
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
  geometry.setIndex(new THREE.BufferAttribute(indices, 1));
  geometry.computeVertexNormals();
  const cut = new THREE.Plane(new THREE.Vector3(0, 0, -1), 0);
  const surfaceMaterial = new THREE.MeshStandardMaterial({
    color: colours.surface, roughness: 0.55, metalness: 0.05, side: THREE.DoubleSide,
  });
  scene.add(new THREE.Mesh(geometry, surfaceMaterial));

  const lo = new THREE.Vector3(...data.surface.lo);
  const hi = new THREE.Vector3(...data.surface.hi);
  const centre = lo.clone().add(hi).multiplyScalar(0.5);
  const radius = Math.max(hi.distanceTo(lo) / 2, 1e-9);
  const camera = new THREE.PerspectiveCamera(35, window.innerWidth / window.innerHeight,
    radius / 100, radius * 100);
  camera.position.copy(centre).add(new THREE.Vector3(1.1, 0.7, 1.6).normalize().multiplyScalar(radius * 3.4));
  scene.add(camera);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x445566, 1.1));
  const key = new THREE.DirectionalLight(0xffffff, 2.2);
  key.position.set(1, 2, 3);
  camera.add(key);
  const controls = new OrbitControls(camera, renderer.domElement);
  controls.target.copy(centre);
  controls.update();

  const field = new BrickField(data.field);
  const sectionGroup = new THREE.Group();
  scene.add(sectionGroup);
  const fillMaterial = new THREE.MeshBasicMaterial({ color: colours.section, side: THREE.DoubleSide });
  const lineMaterial = new THREE.LineBasicMaterial({ color: 0x222222 });
  const inset = makeInset(colours);

  const render = () => renderer.render(scene, camera);
  controls.addEventListener('change', render);
  window.addEventListener('resize', () => {
    camera.aspect = window.innerWidth / window.innerHeight;
    camera.updateProjectionMatrix();
    renderer.setSize(window.innerWidth, window.innerHeight);
    render();
  });

  let state = { on: false, axis: 2, fraction: 0.5 };
  const rangeOf = (axis) => field.range(axis);
  const heightOf = (s) => {
    const [a0, a1] = rangeOf(s.axis);
    return a0 + s.fraction * (a1 - a0);
  };
  const fractionOf = (axis, local) => {
    const [a0, a1] = rangeOf(axis);
    return Math.min(Math.max((local - a0) / (a1 - a0), 0), 1);
  };
  const triangles = data.surface.triangles;
  const panel = makePanel(data.title || 'pgvol view', triangles, (s) => {
    state = s;
    update();
  });

  function clearSection() {
    for (const child of [...sectionGroup.children]) {
      child.geometry.dispose();
      sectionGroup.remove(child);
    }
  }

  function update() {
    clearSection();
    surfaceMaterial.clippingPlanes = [];
    if (!state.on) {
      panel.show('');
      inset.draw(null);
      delete body.dataset.sectionAxis;
      delete body.dataset.sectionHeight;
      delete body.dataset.sectionArea;
      render();
      return;
    }
    const local = state.local ?? heightOf(state);
    delete state.local;
    const [a, ua, va] = planeAxes(state.axis);
    const plane = field.plane(state.axis, local);
    if (!plane) {
      // A height from the address outside the field: say so, and keep the whole surface.
      const [lo, hi] = rangeOf(a);
      const name = 'xyz'[a];
      const world = local + offset[a];
      const span = `${(lo + offset[a]).toPrecision(6)} to ${(hi + offset[a]).toPrecision(6)}`;
      panel.show(`${name} = ${world.toPrecision(6)} is outside the field (${span})`);
      inset.draw(null);
      body.dataset.sectionAxis = name;
      body.dataset.sectionHeight = String(world);
      body.dataset.sectionArea = '0';
      render();
      return;
    }
    const section = contour(plane, data.iso);
    const at = (u, v, out, k) => {
      out[k + a] = local;
      out[k + ua] = u;
      out[k + va] = v;
    };
    const fill3 = new Float32Array((section.fill.length / 2) * 3);
    for (let p = 0, k = 0; p < section.fill.length; p += 2, k += 3) at(section.fill[p], section.fill[p + 1], fill3, k);
    const fillGeometry = new THREE.BufferGeometry();
    fillGeometry.setAttribute('position', new THREE.BufferAttribute(fill3, 3));
    sectionGroup.add(new THREE.Mesh(fillGeometry, fillMaterial));
    const line3 = new Float32Array((section.lines.length / 2) * 3);
    for (let p = 0, k = 0; p < section.lines.length; p += 2, k += 3) at(section.lines[p], section.lines[p + 1], line3, k);
    const lineGeometry = new THREE.BufferGeometry();
    lineGeometry.setAttribute('position', new THREE.BufferAttribute(line3, 3));
    sectionGroup.add(new THREE.LineSegments(lineGeometry, lineMaterial));
    // The surface is cut away above the plane so the filled section shows.
    const normal = new THREE.Vector3();
    normal.setComponent(a, -1);
    cut.set(normal, local);
    surfaceMaterial.clippingPlanes = [cut];
    const [u0, u1] = rangeOf(ua);
    const [v0, v1] = rangeOf(va);
    inset.draw(plane, data.iso, [u0, v0, u1, v1]);
    const world = local + offset[a];
    const name = 'xyz'[a];
    panel.show(`${name} = ${world.toPrecision(6)}   area = ${section.area.toPrecision(6)}`);
    body.dataset.sectionAxis = name;
    body.dataset.sectionHeight = String(world);
    body.dataset.sectionArea = String(section.area);
    render();
  }

  function showSection(wanted) {
    if (!wanted) return false;
    const a = wanted.axis;
    const local = wanted.height - offset[a];
    state = { on: true, axis: a, fraction: fractionOf(a, local), local };
    panel.set(state);
    return true;
  }
  const written = data.section ? { axis: 'xyz'.indexOf(data.section.axis), height: data.section.height } : null;
  showSection(sectionOfHash(window.location.hash)) || showSection(written);
  window.addEventListener('hashchange', () => {
    if (showSection(sectionOfHash(window.location.hash))) update();
  });
  update();
  body.dataset.triangles = String(triangles);
  body.dataset.readyMs = String(Math.round(performance.now()));
  body.dataset.status = 'ready';
}

try {
  start();
} catch (error) {
  document.body.dataset.status = 'error';
  document.body.dataset.error = String(error && error.message ? error.message : error);
  const note = document.createElement('pre');
  note.textContent = `pgvol view: ${document.body.dataset.error}`;
  document.body.append(note);
}
