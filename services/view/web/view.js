// pbnbv view: draws /api/scene with three.js; live scans are polled every second, a scan folder's
// views are chosen with the buttons (or ?view=N). Colours as in the legend (the plan figures'
// occupied blue and frontier orange); flat colours without lighting, so a screenshot can find them.
import * as THREE from 'three';
import { OrbitControls } from '/three/OrbitControls.js';

const COLOURS = { cloud: 0x00c8ff, frontier: 0xff8c00, occupied: 0x3060ff, taken: 0xffffff, chosen: 0xff00ff };
const LOW = new THREE.Color(0x3c3ca0), HIGH = new THREE.Color(0xffe600);

const renderer = new THREE.WebGLRenderer({ antialias: false, preserveDrawingBuffer: true });
renderer.setPixelRatio(1);
renderer.setSize(window.innerWidth, window.innerHeight);
renderer.setClearColor(0x1e1e1e);
document.body.appendChild(renderer.domElement);
const scene = new THREE.Scene();
const camera = new THREE.PerspectiveCamera(40, window.innerWidth / window.innerHeight, 0.01, 20);
camera.up.set(0, 0, 1);  // the object frame's z is up
camera.position.set(1.75, -2.2, 1.4);
const controls = new OrbitControls(camera, renderer.domElement);
controls.target.set(0, 0, 0);
controls.update();
let content = new THREE.Group();
scene.add(content);
scene.add(new THREE.AxesHelper(0.1));

const params = new URLSearchParams(window.location.search);
let chosenView = params.has('view') ? Number(params.get('view')) : -1;  // -1: the latest
let shownKey = '';
const f = (x) => Math.round(x).toLocaleString('en');  // a count for the info line
let shown = null;  // the scene drawn
const hidden = new Set();  // 'ellipsoids', 'candidates': hidden with the keys e and c

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

function draw(s) {
  scene.remove(content);
  content = new THREE.Group();
  if (s.cloud_points > 0) content.add(points(s.cloud, COLOURS.cloud, 3));
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
  const q = s.candidates.map((c) => c.quality_px);
  document.getElementById('info').innerHTML =
    `<b>${s.scan_id || 'waiting for a scan...'}</b> &mdash; view ${s.view}<br>${s.status}<br>` +
    (s.coverage_percent !== null ? `coverage ${s.coverage_percent.toFixed(1)} %<br>` : '') +
    `cloud ${f(s.cloud_points_total)} points (${f(s.cloud_points)} drawn), ${s.frontier_voxels} frontier voxels, ` +
    `${s.ellipsoids.length} ellipsoids<br>` +
    (s.candidates.length ? `${s.candidates.length} candidates, F ${f(Math.min(...q))} .. ${f(Math.max(...q))} px` : 'no plan yet') +
    (s.chosen ? `; chosen view ${chosen_text(s)}` : '') +
    '<br><small>drag to turn, wheel to zoom; keys e, c: ellipsoids, candidates on or off</small>';
  redraw();
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

async function refresh() {
  try {
    const views = await (await fetch('/api/views', { cache: 'no-store' })).json();
    const bar = document.getElementById('views');
    if (!views.live) {
      bar.innerHTML = 'view ' + views.views.map((v) => `<a href="?view=${v}" style="color:${v === chosenView ? '#ff0' : '#ccc'}">${v}</a>`).join(' ');
    } else {
      bar.textContent = 'live';
    }
    const r = await fetch('/api/scene' + (chosenView >= 0 ? `?view=${chosenView}` : ''), { cache: 'no-store' });
    if (r.ok) {
      const text = await r.text();
      if (text !== shownKey) {
        shownKey = text;
        shown = JSON.parse(text);
        draw(shown);
      }
    }
    if (views.live) setTimeout(refresh, 1000);
  } catch (e) {
    document.getElementById('info').textContent = 'pbnbv view: ' + e;
    setTimeout(refresh, 2000);
  }
}

window.addEventListener('resize', () => {
  camera.aspect = window.innerWidth / window.innerHeight;
  camera.updateProjectionMatrix();
  renderer.setSize(window.innerWidth, window.innerHeight);
  redraw();
});
// Drawn in the next few animation frames after a change only (a headless browser shows the
// canvas once a frame is presented; drawing every frame in software would be slow).
let framesToDraw = 0;
function redraw() { framesToDraw = 3; }
renderer.setAnimationLoop(() => {
  if (framesToDraw > 0) {
    framesToDraw -= 1;
    renderer.render(scene, camera);
    // Tells a watcher (the browser test) that the scene of this view is on the canvas.
    if (framesToDraw === 0 && shown) document.title = `pbnbv view ${shown.view} drawn`;
  }
});
controls.addEventListener('change', redraw);
window.addEventListener('keydown', (ev) => {
  const name = { e: 'ellipsoids', c: 'candidates' }[ev.key];
  if (!name) return;
  if (hidden.has(name)) hidden.delete(name); else hidden.add(name);
  const o = content.getObjectByName(name);
  if (o) o.visible = !hidden.has(name);
  redraw();
});
refresh();
