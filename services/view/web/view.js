// pbnbv view: draws a scan's scene with three.js. The page arrives with its first scene in it
// (#initial, put there by the server), drawn before the load event, so that a plain headless
// screenshot shows it; then live scans are polled every second (/api/scene?since=REVISION: 204
// while nothing changed), a scan folder's views are chosen with the links (or ?view=N).
// The cloud is shaded by its normals (a headlight and a key light fixed to the camera, both faces
// lit) over its own colours when it has them, else cyan; the rest keeps flat colours, as in the
// legend (the plan figures' occupied blue and frontier orange). A ground grid of 10 cm cells lies
// on the turntable top, and a corner shows the axes.
import * as THREE from 'three';
import { OrbitControls } from '/three/OrbitControls.js';

const COLOURS = { cloud: 0x00c8ff, frontier: 0xff8c00, occupied: 0x3060ff, taken: 0xffffff, chosen: 0xff00ff,
                  gridMinor: 0x343434, gridMajor: 0x5a5a5a, label: '#aaaaaa' };
const LOW = new THREE.Color(0x3c3ca0), HIGH = new THREE.Color(0xffe600);
const GRID_CELL_M = 0.1, GRID_MAJOR_M = 0.5;  // grid cells, and every fifth line brighter
const CLOUD_POINT_PX = 3;

const holder = document.getElementById('scene');
const renderer = new THREE.WebGLRenderer({ antialias: false, preserveDrawingBuffer: true });
renderer.setPixelRatio(1);
renderer.setClearColor(0x1e1e1e);
holder.appendChild(renderer.domElement);
const scene = new THREE.Scene();
const camera = new THREE.PerspectiveCamera(40, 1, 0.01, 20);
camera.up.set(0, 0, 1);  // the object frame's z is up
camera.position.set(1.75, -2.2, 1.4);
const controls = new OrbitControls(camera, renderer.domElement);
controls.target.set(0, 0, 0);
controls.update();
let content = new THREE.Group();
scene.add(content);
scene.add(new THREE.AxesHelper(0.1));  // the object frame's origin

const params = new URLSearchParams(window.location.search);
const chosenView = params.has('view') ? Number(params.get('view')) : -1;  // -1: the latest
const f = (x) => Math.round(x).toLocaleString('en');  // a count for the info line
let shown = null;  // the scene drawn
const hidden = new Set();  // 'ellipsoids', 'candidates', 'grid': hidden with the keys e, c and g
// What is drawn, for a watcher (the browser test) and the console.
window.pbnbvView = { view: null, cloud: null, grid: null };

// --- the cloud: points shaded in the vertex shader (one colour per point and frame, cheap for
// 100,000s of points). nrm: the point's unit normal (0 0 0: none, drawn evenly lit); rgb: its
// colour when the cloud has colours (HAS_RGB), else `base`. Both lights are fixed to the camera
// (view space): a headlight along the line of sight and a key light from above left; a normal
// lights the same from either side, so a surface seen from behind is not dark.
const CLOUD_VERTEX = `
attribute vec3 nrm;
#ifdef HAS_RGB
attribute vec3 rgb;
#endif
uniform vec3 base;
uniform float size;
varying vec3 shade;
const vec3 KEY = vec3(-0.4472, 0.7454, 0.4969);  // unit, view space
void main() {
  vec4 eye = modelViewMatrix * vec4(position, 1.0);
  gl_Position = projectionMatrix * eye;
  gl_PointSize = size;
#ifdef HAS_RGB
  vec3 colour = rgb;
#else
  vec3 colour = base;
#endif
  float light = 0.75;
  if (dot(nrm, nrm) > 0.25) {
    vec3 n = normalize(normalMatrix * nrm);
    float head = abs(dot(n, normalize(-eye.xyz)));
    float key = abs(dot(n, KEY));
    light = 0.12 + 0.4 * head + 0.55 * key;
  }
  shade = clamp(colour * light, 0.0, 1.0);
}`;
const CLOUD_FRAGMENT = `
varying vec3 shade;
void main() { gl_FragColor = vec4(shade, 1.0); }`;

// The scene's cloud: positions, normals as bytes (-127..127), colours as bytes when present.
function cloudPoints(s) {
  const n = s.cloud_points;
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.Float32BufferAttribute(s.cloud, 3));
  const normals = Array.isArray(s.cloud_normals) && s.cloud_normals.length === 3 * n;
  g.setAttribute('nrm', new THREE.BufferAttribute(normals ? Int8Array.from(s.cloud_normals) : new Int8Array(3 * n), 3, true));
  const colours = Array.isArray(s.cloud_colours) && s.cloud_colours.length === 3 * n;
  if (colours) g.setAttribute('rgb', new THREE.BufferAttribute(Uint8Array.from(s.cloud_colours), 3, true));
  // The base colour as written (sRGB): the shader's output is not colour-managed.
  const m = new THREE.ShaderMaterial({
    defines: colours ? { HAS_RGB: 1 } : {},
    uniforms: { base: { value: new THREE.Vector3(((COLOURS.cloud >> 16) & 255) / 255, ((COLOURS.cloud >> 8) & 255) / 255,
                                                 (COLOURS.cloud & 255) / 255) },
                size: { value: CLOUD_POINT_PX } },
    vertexShader: CLOUD_VERTEX, fragmentShader: CLOUD_FRAGMENT });
  const p = new THREE.Points(g, m);
  p.name = 'cloud';
  window.pbnbvView.cloud = { points: n, normals: normals, colours: colours };
  return p;
}

function points(flat, colour, size) {
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.Float32BufferAttribute(flat, 3));
  return new THREE.Points(g, new THREE.PointsMaterial({ color: colour, size: size, sizeAttenuation: false }));
}

function poseMatrix(p) {
  const q = p.quat_wxyz, t = p.position_m;
  return new THREE.Matrix4().compose(new THREE.Vector3(t[0], t[1], t[2]),
                                     new THREE.Quaternion(q[1], q[2], q[3], q[0]), new THREE.Vector3(1, 1, 1));
}

// A camera as a small frustum (optical frame: z forward, x right, y down), apex at the centre.
function frustum(p, colour, depth) {
  const w = depth * 0.9, h = depth * 0.5;
  const c = [[-w, -h], [w, -h], [w, h], [-w, h]];
  const v = [];
  for (let i = 0; i < 4; ++i) {
    const a = c[i], b = c[(i + 1) % 4];
    v.push(0, 0, 0, a[0], a[1], depth, a[0], a[1], depth, b[0], b[1], depth);
  }
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.Float32BufferAttribute(v, 3));
  const l = new THREE.LineSegments(g, new THREE.LineBasicMaterial({ color: colour }));
  l.matrixAutoUpdate = false;
  l.matrix.copy(poseMatrix(p));
  return l;
}

// --- text as sprites: `px` pixels tall on the screen whatever the distance (perspective
// camera), or `world` units tall (the axes corner's orthographic camera).
function textSprite(text, colour, px, world) {
  const font = 28;
  const c = document.createElement('canvas');
  const ctx = c.getContext('2d');
  ctx.font = `${font}px sans-serif`;
  c.width = Math.ceil(ctx.measureText(text).width) + 8;
  c.height = font + 8;
  ctx.font = `${font}px sans-serif`;
  ctx.fillStyle = colour;
  ctx.textBaseline = 'middle';
  ctx.fillText(text, 4, c.height / 2);
  const t = new THREE.CanvasTexture(c);
  t.colorSpace = THREE.SRGBColorSpace;
  const s = new THREE.Sprite(new THREE.SpriteMaterial({ map: t, depthTest: false, transparent: true, sizeAttenuation: !px }));
  s.renderOrder = 10;
  s.userData.aspect = c.width / c.height;
  if (px) {
    s.userData.px = px;
    fitLabel(s);
  } else {
    s.scale.set(world * s.userData.aspect, world, 1);
  }
  return s;
}
// A screen-sized label's scale for the canvas' current height (three scales such a sprite by the
// projection only: its height on the screen is scale * P[1][1] * H / 2 pixels).
function fitLabel(s) {
  const h = Math.max(1, renderer.domElement.height);
  const k = 2 * s.userData.px / (camera.projectionMatrix.elements[5] * h);
  s.scale.set(k * s.userData.aspect, k, 1);
}

// --- the ground grid: GRID_CELL_M cells on the plane z = ground (the turntable top; z = 0 while
// the server does not know it), square about the turntable's axis and wide enough for every
// candidate and view, brighter every GRID_MAJOR_M, those lines labelled in metres along x.
function ground(s) {
  let r = 0.25;
  const reach = (p) => { r = Math.max(r, Math.abs(p[0]), Math.abs(p[1])); };
  s.candidates.forEach((c) => reach(c.pose.position_m));
  s.views_taken.forEach((p) => reach(p.position_m));
  if (s.chosen) reach(s.chosen.position_m);
  for (let i = 0; i < s.cloud.length; i += 3 * 64) reach([s.cloud[i], s.cloud[i + 1]]);
  const half = Math.min(3, Math.ceil((r + 0.05) / GRID_CELL_M - 1e-6) * GRID_CELL_M);
  const z = s.ground ? s.ground.z_m : 0;
  const pos = [], col = [];
  const minor = new THREE.Color(COLOURS.gridMinor), major = new THREE.Color(COLOURS.gridMajor);
  const cells = Math.round(half / GRID_CELL_M);
  let lines = 0;
  for (let i = -cells; i <= cells; ++i) {
    const u = i * GRID_CELL_M;
    const k = i % Math.round(GRID_MAJOR_M / GRID_CELL_M) === 0 ? major : minor;
    pos.push(u, -half, z, u, half, z, -half, u, z, half, u, z);
    for (let j = 0; j < 4; ++j) col.push(k.r, k.g, k.b);
    lines += 2;
  }
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.Float32BufferAttribute(pos, 3));
  g.setAttribute('color', new THREE.Float32BufferAttribute(col, 3));
  const grid = new THREE.Group();
  grid.name = 'grid';
  grid.add(new THREE.LineSegments(g, new THREE.LineBasicMaterial({ vertexColors: true })));
  // Labels along the x axis (beside the object, where the view opens) and, in the cell just beyond
  // the first, the cell's size.
  for (let u = GRID_MAJOR_M; u <= half + 1e-9; u += GRID_MAJOR_M) {
    const t = textSprite(`${+u.toFixed(1)} m`, COLOURS.label, 13);
    t.position.set(u, -0.5 * GRID_CELL_M, z);
    grid.add(t);
  }
  if (GRID_MAJOR_M + GRID_CELL_M <= half + 1e-9) {
    const cell = textSprite(`${Math.round(GRID_CELL_M * 100)} cm`, COLOURS.label, 11);
    cell.position.set(GRID_MAJOR_M + 0.5 * GRID_CELL_M, 0.5 * GRID_CELL_M, z);
    grid.add(cell);
  }
  grid.visible = !hidden.has('grid');
  const where = s.ground ? `${s.ground.what}, z = ${s.ground.z_m.toFixed(3)} m` : 'z = 0 (the turntable top is not known yet)';
  document.getElementById('scale').innerHTML =
    `<span style="border:1px solid #777;box-sizing:border-box"></span>grid: ${Math.round(GRID_CELL_M * 100)} cm cells, ` +
    `lines every ${Math.round(GRID_MAJOR_M * 100)} cm brighter (labelled in m along x), ${+(2 * half).toFixed(1)} m across, on ${where}`;
  window.pbnbvView.grid = { cell_m: GRID_CELL_M, major_m: GRID_MAJOR_M, half_m: half, z_m: z, lines: lines,
                            where: s.ground ? s.ground.what : null };
  return grid;
}

// --- the axes corner: x, y, z from the object frame's origin, turned as the main camera looks.
const GIZMO_PX = 96;
const gizmo = new THREE.Scene();
const gizmoCamera = new THREE.OrthographicCamera(-1.7, 1.7, 1.7, -1.7, 0.1, 10);
[[1, 0, 0, 0xff5050, 'x'], [0, 1, 0, 0x50e050, 'y'], [0, 0, 1, 0x5080ff, 'z']].forEach(([x, y, z, c, name]) => {
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.Float32BufferAttribute([0, 0, 0, x, y, z], 3));
  gizmo.add(new THREE.LineSegments(g, new THREE.LineBasicMaterial({ color: c })));
  const head = new THREE.Mesh(new THREE.ConeGeometry(0.1, 0.3, 10), new THREE.MeshBasicMaterial({ color: c }));
  head.position.set(x, y, z);
  head.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), new THREE.Vector3(x, y, z));
  gizmo.add(head);
  const t = textSprite(name, '#' + c.toString(16).padStart(6, '0'), 0, 0.55);
  t.position.set(1.38 * x, 1.38 * y, 1.38 * z);
  gizmo.add(t);
});

function render() {
  const size = renderer.getSize(new THREE.Vector2()), w = size.x, h = size.y;  // CSS pixels, as setViewport takes
  renderer.setViewport(0, 0, w, h);
  renderer.render(scene, camera);
  gizmoCamera.position.copy(camera.position).sub(controls.target).setLength(5);
  gizmoCamera.up.copy(camera.up);
  gizmoCamera.lookAt(0, 0, 0);
  renderer.autoClear = false;
  renderer.setScissorTest(true);
  renderer.setScissor(6, 6, GIZMO_PX, GIZMO_PX);
  renderer.setViewport(6, 6, GIZMO_PX, GIZMO_PX);
  renderer.clearDepth();
  renderer.render(gizmo, gizmoCamera);
  renderer.setScissorTest(false);
  renderer.setViewport(0, 0, w, h);
  renderer.autoClear = true;
}

function resize() {
  const w = Math.max(1, holder.clientWidth), h = Math.max(1, holder.clientHeight);
  camera.aspect = w / h;
  camera.updateProjectionMatrix();
  renderer.setSize(w, h);
  content.traverse((o) => { if (o.userData.px) fitLabel(o); });
}

function draw(s) {
  scene.remove(content);
  content.traverse((o) => {
    if (o.geometry) o.geometry.dispose();
    if (o.material) { if (o.material.map) o.material.map.dispose(); o.material.dispose(); }
  });
  content = new THREE.Group();
  content.add(ground(s));
  window.pbnbvView.cloud = { points: 0, normals: false, colours: false };
  if (s.cloud_points > 0) content.add(cloudPoints(s));
  if (s.frontier_voxels > 0) content.add(points(s.frontier, COLOURS.frontier, 5));
  const ellipsoids = new THREE.Group();
  ellipsoids.name = 'ellipsoids';
  ellipsoids.visible = !hidden.has('ellipsoids');
  content.add(ellipsoids);
  for (const e of s.ellipsoids) {
    const m = new THREE.Mesh(new THREE.SphereGeometry(1, 12, 8),
                             new THREE.MeshBasicMaterial({ color: e.frontier ? COLOURS.frontier : COLOURS.occupied, wireframe: true,
                                                           transparent: true, opacity: 0.5 }));
    m.position.set(...e.centre_m);
    m.quaternion.set(...e.quat_xyzw);
    m.scale.set(...e.scale_m);
    ellipsoids.add(m);
  }
  if (s.candidates.length > 0) {
    const pos = [], col = [];
    for (const c of s.candidates) {
      pos.push(...c.pose.position_m);
      const k = LOW.clone().lerp(HIGH, c.shade);
      col.push(k.r, k.g, k.b);
    }
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.Float32BufferAttribute(pos, 3));
    g.setAttribute('color', new THREE.Float32BufferAttribute(col, 3));
    const c = new THREE.Points(g, new THREE.PointsMaterial({ vertexColors: true, size: 5, sizeAttenuation: false }));
    c.name = 'candidates';
    c.visible = !hidden.has('candidates');
    content.add(c);
  }
  s.views_taken.forEach((p) => content.add(frustum(p, COLOURS.taken, 0.08)));
  if (s.chosen) {
    content.add(frustum(s.chosen, COLOURS.chosen, 0.12));
    const ball = new THREE.Mesh(new THREE.SphereGeometry(0.05, 16, 12), new THREE.MeshBasicMaterial({ color: COLOURS.chosen }));
    ball.position.set(...s.chosen.position_m);
    content.add(ball);
  }
  scene.add(content);
  window.pbnbvView.view = s.view;
  const q = s.candidates.map((c) => c.quality_px);
  const look = window.pbnbvView.cloud;
  document.getElementById('info').innerHTML =
    `<b>${escapeHtml(s.scan_id) || 'waiting for a scan...'}</b><br>${s.view > 0 ? `view ${s.view}` : 'no view yet'}<br>${escapeHtml(s.status)}<br>` +
    (s.coverage_percent !== null ? `coverage ${s.coverage_percent.toFixed(1)} %<br>` : '') +
    `cloud ${f(s.cloud_points_total)} points (${f(s.cloud_points)} drawn` +
    (s.cloud_points > 0 ? `, ${look.colours ? 'its colours' : 'cyan'}${look.normals ? ' shaded by normals' : ', no normals'}` : '') +
    `), ${s.frontier_voxels} frontier voxels, ${s.ellipsoids.length} ellipsoids<br>` +
    (s.candidates.length ? `${s.candidates.length} candidates, F ${f(Math.min(...q))} .. ${f(Math.max(...q))} px` : 'no plan yet') +
    (s.chosen ? `<br>chosen view: ${chosen_text(s)}` : '');
  redraw();
}

function escapeHtml(t) {
  return String(t ?? '').replace(/[&<>"]/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;' })[c]);
}

// What the plan ranked its chosen view by (VIEW_PLAN's ranking).
function chosen_text(s) {
  switch (s.chosen_ranking) {
    case 'gap_deg': return `fills a gap, ${s.chosen_quality_px.toFixed(1)}&deg; from the nearest view`;
    case 'unobserved_voxels': return `sees ${f(s.chosen_quality_px)} unobserved voxels`;
    case 'true_samples': return `sees ${f(s.chosen_quality_px)} new true surface samples`;
    case 'random': return 'drawn at random';
    case 'combined': return `combined score ${s.chosen_quality_px.toFixed(2)} of 3 (F, gap, rays)`;
    default: return `F ${f(s.chosen_quality_px)} px`;
  }
}

function showViews(views) {
  const bar = document.getElementById('views');
  if (!views.live) {
    bar.innerHTML = 'view ' + views.views.map((v) => `<a href="?view=${v}" style="color:${v === chosenView ? '#ff0' : '#ccc'}">${v}</a>`).join(' ');
  } else {
    bar.textContent = 'live';
  }
}

function noView() {
  document.getElementById('info').textContent = `pbnbv view: this scan has no view ${chosenView}`;
}

// The scene again when it has changed (the server answers 204 while the revision shown is current).
async function refresh() {
  try {
    const views = await (await fetch('/api/views', { cache: 'no-store' })).json();
    showViews(views);
    const q = new URLSearchParams();
    if (chosenView >= 0) q.set('view', chosenView);
    if (shown && shown.revision > 0) q.set('since', shown.revision);
    const r = await fetch('/api/scene?' + q, { cache: 'no-store' });
    if (r.status === 200) {
      shown = await r.json();
      draw(shown);
    } else if (r.status === 404) {
      noView();
    }
    if (views.live) setTimeout(refresh, 1000);
  } catch (e) {
    document.getElementById('info').textContent = 'pbnbv view: ' + e;
    setTimeout(refresh, 2000);
  }
}

window.addEventListener('resize', () => { resize(); redraw(); });
// Drawn at once when the scene changes, and again in the next few animation frames (a headless
// browser shows the canvas once a frame is presented; drawing every frame in software is slow).
let framesToDraw = 0;
function redraw() { framesToDraw = 3; }
renderer.setAnimationLoop(() => {
  if (framesToDraw > 0) {
    framesToDraw -= 1;
    render();
    // Tells a watcher (the browser test) that the scene of this view is on the canvas.
    if (framesToDraw === 0 && shown) document.title = `pbnbv view ${shown.view} drawn`;
  }
});
controls.addEventListener('change', redraw);
window.addEventListener('keydown', (ev) => {
  const name = { e: 'ellipsoids', c: 'candidates', g: 'grid' }[ev.key];
  if (!name) return;
  if (hidden.has(name)) hidden.delete(name); else hidden.add(name);
  const o = content.getObjectByName(name);
  if (o) o.visible = !hidden.has(name);
  redraw();
});

// The first scene, from the page itself: drawn now, before the load event.
resize();
const initial = JSON.parse(document.getElementById('initial').textContent || 'null');
if (initial) {
  showViews(initial.views);
  if (initial.scene) {
    shown = initial.scene;
    draw(shown);
    render();
  } else if (chosenView >= 0) {
    noView();
  }
  if (initial.views.live) setTimeout(refresh, 1000);
} else {
  refresh();  // a page not served by pbnbv view (e.g. opened from a file): fetch it
}
