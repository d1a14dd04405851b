// The viewer page (web/viewer.html): open a baked file (drop, picker or ?url=), refine every
// object with the runtime's kernels at the level the view calls for (or a forced one), draw
// every instance through the file's camera or an automatic one, orbit or fly. Without WebGPU
// (no navigator.gpu, no adapter, or ?present=webgl2) the objects are refined on the CPU in
// WebAssembly and drawn with WebGL2 (webgl_scene.js); the page says which path it uses. Every
// error is shown on the page; none escapes.
import { createRuntime, loadAsset, HceScene, resolveCamera, assetBounds, HceError } from './index.js';
import { GlScene, webgl2Context } from './webgl_scene.js';
import { add, cross, dot, length, normalize, scale, sub } from './math.js';

/** @typedef {import('./view.js').Camera} Camera */

const $ = (/** @type {string} */ id) => /** @type {HTMLElement} */ (document.getElementById(id));
const canvas = /** @type {HTMLCanvasElement} */ ($('canvas'));
const q = new URLSearchParams(location.search);

/**
 * What tests and scripts can read: `state` is 'starting', 'compiling', 'loading', 'ready' or
 * 'error'; `frameMs` the wall time of the last frame, from choosing its levels to the GPU done
 * (its refinements included).
 */
const status = { present: '', state: 'starting', error: /** @type {string | null} */ (null), frames: 0, levels: /** @type {number[]} */ ([]), triangles: 0, camera: /** @type {Camera | null} */ (null), frameMs: 0 };
/** @type {any} */ (window).hceViewer = status;
/** Opens a URL as ?url= does; resolves when it is shown or refused (for tests and scripts). */
/** @type {any} */ (window).hceOpen = (/** @type {string} */ url) => openUrl(url);

/** @param {string} text */
function setStatus(text) {
  $('status').textContent = text;
}

/**
 * Shows an error on the page; the viewer stays usable for the next file.
 * @param {unknown} e
 * @param {string} [line] the status line: what failed
 */
function showError(e, line = 'could not open the file') {
  console.error(e instanceof Error ? e.stack : String(e));
  const message = e instanceof HceError ? e.message : e instanceof Error ? `${e.name}: ${e.message}` : String(e);
  status.state = 'error';
  status.error = message;
  const box = $('error');
  box.textContent = message;
  box.classList.add('shown');
  setStatus(line);
}

function clearError() {
  status.error = null;
  $('error').classList.remove('shown');
  $('error').textContent = '';
}

// The fixed size of a screenshot (?size=WxH), else the element's size.
const fixedSize = q.get('size')?.match(/^(\d+)x(\d+)$/);
function resize() {
  const w = fixedSize ? Number(fixedSize[1]) : Math.max(1, Math.round(canvas.clientWidth * devicePixelRatio));
  const h = fixedSize ? Number(fixedSize[2]) : Math.max(1, Math.round(canvas.clientHeight * devicePixelRatio));
  if (canvas.width !== w || canvas.height !== h) {
    canvas.width = w;
    canvas.height = h;
  }
  if (fixedSize) {
    canvas.style.width = `${w}px`;
    canvas.style.height = `${h}px`;
  }
}

/** The camera the user moves: eye and target (orbit around the target, or fly). */
const view = {
  /** @type {Camera | null} */
  camera: null,
  /** @type {Camera | null} */
  initial: null,
  mode: 'orbit',
  keys: new Set(),
};

let runtime = /** @type {Awaited<ReturnType<typeof createRuntime>> | null} */ (null);
let scene = /** @type {HceScene | GlScene | null} */ (null);
let bounds = /** @type {import('./math.js').Bounds | null} */ (null);
let busy = false;
let dirty = true;

/**
 * Whether WebGPU can present to a canvas here, tried on a throwaway device: headless Chromium
 * on SwiftShader loses the device at the first frame, and the page then draws through a
 * read-back instead.
 */
async function canvasPresents() {
  const adapter = await navigator.gpu.requestAdapter();
  if (!adapter) return false;
  const device = await adapter.requestDevice();
  let lost = false;
  device.lost.then(() => { lost = true; });
  const probe = document.createElement('canvas');
  probe.width = probe.height = 4;
  const ctx = /** @type {GPUCanvasContext} */ (probe.getContext('webgpu'));
  ctx.configure({ device, format: navigator.gpu.getPreferredCanvasFormat(), alphaMode: 'opaque' });
  const encoder = device.createCommandEncoder();
  encoder.beginRenderPass({ colorAttachments: [{ view: ctx.getCurrentTexture().createView(), loadOp: 'clear', storeOp: 'store' }] }).end();
  device.queue.submit([encoder.finish()]);
  try {
    await device.queue.onSubmittedWorkDone();
    await new Promise((r) => requestAnimationFrame(r));
    await device.queue.onSubmittedWorkDone();
  } catch {
    return false;
  }
  device.destroy();
  return !lost;
}

/**
 * How frames reach the screen: a WebGPU canvas, a WebGPU read-back drawn into a 2D canvas, or
 * WebGL2 (refined on the CPU).
 */
let present = /** @type {{ kind: 'webgpu', context: GPUCanvasContext } | { kind: '2d', context: CanvasRenderingContext2D } | { kind: 'webgl2', gl: WebGL2RenderingContext } | null} */ (null);

/** Why WebGPU cannot be used here, or null when it can (an adapter is offered). */
async function webgpuMissing() {
  if (q.get('present') === 'webgl2') return 'WebGL2 asked for with ?present=webgl2';
  if (!navigator.gpu) return 'this browser has no WebGPU (navigator.gpu)';
  if (!(await navigator.gpu.requestAdapter())) return 'WebGPU gives no adapter on this machine';
  return null;
}

/** @param {string} text */
function setPath(text) {
  $('path').textContent = text;
}

async function start() {
  const missing = await webgpuMissing();
  if (missing !== null) {
    const gl = webgl2Context(canvas);
    if (!gl) throw new Error(`this browser has neither WebGPU (${missing}) nor WebGL2`);
    present = { kind: 'webgl2', gl };
    status.present = present.kind;
    setPath(`Drawn with WebGL2, refined on the CPU in WebAssembly: ${missing}.`);
    return started();
  }
  status.state = 'compiling';
  setStatus('compiling the kernels (seconds on a software adapter)…');
  const wanted = q.get('present');
  const webgpu = wanted === 'canvas' || (wanted !== 'readback' && (await canvasPresents()));
  const format = webgpu ? navigator.gpu.getPreferredCanvasFormat() : 'rgba8unorm';
  const wgslBase = new URL(q.get('wgsl') ?? '../runtime/src/gpu/', location.href);
  const progress = /** @type {HTMLProgressElement} */ ($('progress'));
  runtime = await createRuntime({
    wgslBase,
    canvasFormat: format,
    progress: (done, total, label) => {
      progress.max = total;
      progress.value = done;
      setStatus(`compiling the kernels: ${done} of ${total} pipelines (${label})`);
    },
  });
  runtime.device.lost.then((info) => showError(`the GPU device was lost: ${info.message}`, 'the GPU device was lost'));
  if (webgpu) {
    const context = /** @type {GPUCanvasContext} */ (canvas.getContext('webgpu'));
    context.configure({ device: runtime.device, format, alphaMode: 'opaque' });
    present = { kind: 'webgpu', context };
  } else {
    present = { kind: '2d', context: /** @type {CanvasRenderingContext2D} */ (canvas.getContext('2d')) };
  }
  status.present = present.kind;
  setPath(`Drawn with WebGPU, refined on the GPU by the runtime's kernels${present.kind === '2d' ? ' (shown through a read-back: this canvas cannot present WebGPU)' : ''}.`);
  return started();
}

/** The page ready for files: ?url= opened, frames drawn from now on. */
async function started() {
  status.state = 'idle';
  setStatus('open a baked .glb, .gltf or .hce');
  const url = q.get('url');
  if (url) await openUrl(url);
  requestAnimationFrame(function frame() {
    try {
      tick();
    } catch (e) {
      showError(e);
    }
    requestAnimationFrame(frame);
  });
}

/** @param {string} url */
async function openUrl(url) {
  status.state = 'loading';
  await guarded(async () => {
    const response = await fetch(url);
    if (!response.ok) throw new Error(`cannot load ${url}: HTTP ${response.status}`);
    const base = new URL(url, location.href);
    await open(new Uint8Array(await response.arrayBuffer()), url.split('/').pop() ?? url, async (uri) => {
      const r = await fetch(new URL(uri, base));
      if (!r.ok) throw new Error(`HTTP ${r.status}`);
      return new Uint8Array(await r.arrayBuffer());
    });
  });
}

/** @param {() => Promise<void>} f */
async function guarded(f) {
  try {
    await f();
  } catch (e) {
    showError(e);
  }
}

/**
 * @param {Uint8Array} bytes
 * @param {string} name
 * @param {((uri: string) => Promise<Uint8Array>) | undefined} resolveUri
 */
async function open(bytes, name, resolveUri) {
  if (!runtime && present?.kind !== 'webgl2') return;
  clearError();
  status.state = 'loading';
  setStatus(`reading ${name}…`);
  scene?.destroy();
  scene = null;
  const asset = await loadAsset(bytes, { name, resolveUri });
  const reconstruction = /** @type {any} */ ($('recon')).value;
  // Flat objects are drawn from their trees (SPEC.md F.7.1) unless ?flat=uniform.
  const flatRefinement = q.get('flat') === 'uniform' ? 'uniform' : 'adaptive';
  const options = { reconstruction, flatRefinement: /** @type {import('./native.js').FlatRefinement} */ (flatRefinement) };
  const next = present?.kind === 'webgl2' ? new GlScene(present.gl, asset, options) : new HceScene(/** @type {NonNullable<typeof runtime>} */ (runtime).kernels, asset, options);
  next.upload();
  const forced = q.get('level');
  if (forced !== null) for (const o of next.objects) o.forced = Math.max(0, Math.min(6, Number(forced)));
  resize();
  const resolved = resolveCamera(asset, canvas.width / canvas.height, q.get('camera') === 'auto' ? 'auto' : 'scene-or-auto');
  if (resolved === null) throw new HceError('', `${name} has nothing to draw (no object is used by a node of the scene)`);
  bounds = assetBounds(asset);
  if (bounds) {
    // Orbit about the point straight ahead nearest the scene's centre, not the file's target (a
    // direction only, placed at the scene's radius), as `hce view` does.
    const c = resolved.camera;
    const forward = normalize(sub(c.target, c.eye));
    const centre = scale(add(bounds.min, bounds.max), 0.5);
    const radius = Math.max(0.5 * length(sub(bounds.max, bounds.min)), 1e-3);
    const ahead = Math.min(Math.max(dot(sub(centre, c.eye), forward), 0.05 * radius), 2 * radius);
    resolved.camera.target = add(c.eye, scale(forward, ahead));
  }
  view.camera = { ...resolved.camera };
  view.initial = { ...resolved.camera };
  $('camera').textContent = `through ${resolved.source}`;
  $('warnings').textContent = asset.warnings.join('\n');
  scene = next;
  buildTable();
  dirty = true;
  status.state = 'ready';
  setStatus(`${name}: ${asset.objects.length} objects (${asset.format})`);
}

function buildTable() {
  const body = /** @type {HTMLTableSectionElement} */ (document.querySelector('#objects tbody'));
  body.textContent = '';
  if (!scene) return;
  scene.objects.forEach((o, i) => {
    const row = body.insertRow();
    row.insertCell().textContent = `${o.source.object.name}${o.source.object.kind === 'flat' ? ' (flat)' : ''}${o.source.instances.length > 1 ? ` ×${o.source.instances.length}` : ''}`;
    const cell = row.insertCell();
    const select = document.createElement('select');
    select.dataset.object = String(i);
    if (o.source.object.kind === 'flat') {
      select.innerHTML = q.get('flat') === 'uniform' ? '<option value="">tree depth</option>' : '<option value="">trees</option>';
      select.disabled = true;
    } else {
      select.innerHTML = '<option value="">auto</option>' + [0, 1, 2, 3, 4, 5, 6].map((l) => `<option value="${l}">${l}</option>`).join('');
      select.value = o.forced === null ? '' : String(o.forced);
      select.addEventListener('change', () => {
        o.forced = select.value === '' ? null : Number(select.value);
        dirty = true;
      });
    }
    cell.append(select, document.createElement('span'));
    row.insertCell().className = 'num';
    row.insertCell().className = 'num';
  });
}

function updateTable() {
  if (!scene) return;
  const rows = /** @type {HTMLTableSectionElement} */ (document.querySelector('#objects tbody')).rows;
  scene.objects.forEach((o, i) => {
    const row = rows[i];
    if (!row) return;
    /** @type {HTMLElement} */ (row.cells[1].lastChild).textContent = o.level >= 0 ? ` ${o.level}` : ' –';
    row.cells[2].textContent = o.refined ? (o.refined.triangleCount * o.source.instances.length).toLocaleString('en') : '–';
    row.cells[3].textContent = o.refined ? o.refineMs.toFixed(1) : '–';
  });
  $('totals').textContent = `${scene.drawnTriangles().toLocaleString('en')} triangles drawn`;
}

/** Moves the fly camera by the keys held. */
function fly() {
  const c = view.camera;
  if (!c || view.mode !== 'fly' || view.keys.size === 0 || !bounds) return;
  const step = 0.01 * length(sub(bounds.max, bounds.min));
  const forward = normalize(sub(c.target, c.eye));
  const right = normalize(cross(forward, [0, 1, 0]));
  let move = [0, 0, 0];
  if (view.keys.has('w')) move = add(move, forward);
  if (view.keys.has('s')) move = sub(move, forward);
  if (view.keys.has('d')) move = add(move, right);
  if (view.keys.has('a')) move = sub(move, right);
  if (view.keys.has('e')) move = add(move, [0, 1, 0]);
  if (view.keys.has('q')) move = sub(move, [0, 1, 0]);
  const delta = scale(move, step);
  c.eye = add(c.eye, delta);
  c.target = add(c.target, delta);
  dirty = true;
}

function tick() {
  fly();
  if (!(runtime?.renderer || present?.kind === 'webgl2') || !scene || !view.camera || !bounds || busy) return;
  resize();
  if (!dirty) return;
  dirty = false;
  busy = true;
  const t0 = performance.now();
  const current = scene;
  const camera = { ...view.camera };
  const levels = current.levelsFor(camera, canvas.height);
  current.refineTo(levels).then(() => {
    if (current !== scene || !bounds) return;
    const ev = Number(/** @type {HTMLInputElement} */ ($('exposure')).value);
    if (current instanceof GlScene) {
      current.render(camera, bounds, ev);
      // readPixels waits for the frame, so that frameMs counts the drawing too.
      const gl = current.gl;
      gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, new Uint8Array(4));
      finishFrame(current, camera, t0);
      return;
    }
    if (!runtime?.renderer) return;
    if (present?.kind === 'webgpu') {
      runtime.renderer.render(current, camera, bounds, present.context.getCurrentTexture(), ev);
    } else if (present?.kind === '2d') {
      const context = present.context;
      const [w, h] = [canvas.width, canvas.height];
      return runtime.renderer.renderToPixels(current, camera, bounds, w, h, ev).then((pixels) => {
        context.putImageData(new ImageData(pixels, w, h), 0, 0);
        finishFrame(current, camera, t0);
      });
    }
    return runtime.device.queue.onSubmittedWorkDone().then(() => finishFrame(current, camera, t0));
  }).catch(showError).finally(() => {
    busy = false;
  });
}

/** @param {HceScene | GlScene} current @param {Camera} camera @param {number} t0 when the frame began */
function finishFrame(current, camera, t0) {
  status.frameMs = performance.now() - t0;
  status.levels = current.objects.map((o) => o.level);
  status.triangles = current.drawnTriangles();
  status.camera = camera;
  status.frames += 1;
  updateTable();
}

// Input: orbit (drag), pan (right or shift drag), zoom (wheel), fly (keys and drag to look).
let drag = /** @type {{ x: number, y: number, pan: boolean } | null} */ (null);
canvas.addEventListener('contextmenu', (e) => e.preventDefault());
canvas.addEventListener('pointerdown', (e) => {
  canvas.setPointerCapture(e.pointerId);
  drag = { x: e.clientX, y: e.clientY, pan: e.button === 2 || e.shiftKey };
});
canvas.addEventListener('pointerup', () => { drag = null; });
canvas.addEventListener('pointermove', (e) => {
  const c = view.camera;
  if (!drag || !c) return;
  const dx = e.clientX - drag.x;
  const dy = e.clientY - drag.y;
  drag.x = e.clientX;
  drag.y = e.clientY;
  const offset = sub(c.eye, c.target);
  const dist = length(offset);
  const forward = normalize(scale(offset, -1));
  const right = normalize(cross(forward, [0, 1, 0]));
  const up = cross(right, forward);
  if (drag.pan) {
    const k = (dist * 2 * Math.tan((c.fovYDegrees * Math.PI) / 360)) / canvas.clientHeight;
    const delta = add(scale(right, -dx * k), scale(up, dy * k));
    c.eye = add(c.eye, delta);
    c.target = add(c.target, delta);
  } else {
    // Yaw about +Y, pitch about the right axis, kept off the poles.
    const yaw = -dx * 0.008;
    const pitch = -dy * 0.008;
    const rot = (/** @type {number[]} */ v) => [v[0] * Math.cos(yaw) + v[2] * Math.sin(yaw), v[1], -v[0] * Math.sin(yaw) + v[2] * Math.cos(yaw)];
    let dir = rot(view.mode === 'fly' ? forward : offset.map((x) => x / dist));
    const elevation = Math.asin(Math.max(-1, Math.min(1, dir[1])));
    const next = Math.max(-1.5, Math.min(1.5, elevation + (view.mode === 'fly' ? -pitch : pitch)));
    const flat = normalize([dir[0], 0, dir[2]]);
    dir = [flat[0] * Math.cos(next), Math.sin(next), flat[2] * Math.cos(next)];
    if (view.mode === 'fly') c.target = add(c.eye, scale(dir, dist));
    else c.eye = add(c.target, scale(dir, dist));
  }
  dirty = true;
});
canvas.addEventListener('wheel', (e) => {
  const c = view.camera;
  if (!c) return;
  e.preventDefault();
  const offset = sub(c.eye, c.target);
  c.eye = add(c.target, scale(offset, Math.exp(e.deltaY * 0.001)));
  dirty = true;
}, { passive: false });
window.addEventListener('keydown', (e) => {
  if (e.target instanceof HTMLInputElement || e.target instanceof HTMLSelectElement) return;
  view.keys.add(e.key.toLowerCase());
});
window.addEventListener('keyup', (e) => view.keys.delete(e.key.toLowerCase()));
window.addEventListener('resize', () => { dirty = true; });
$('mode').addEventListener('change', (e) => { view.mode = /** @type {HTMLSelectElement} */ (e.target).value; });
$('reset').addEventListener('click', () => {
  if (view.initial) view.camera = { ...view.initial };
  dirty = true;
});
$('exposure').addEventListener('input', (e) => {
  $('ev').textContent = /** @type {HTMLInputElement} */ (e.target).value;
  dirty = true;
});
$('recon').addEventListener('change', (e) => {
  guarded(async () => {
    scene?.setReconstruction(/** @type {any} */ (e.target).value);
    scene?.upload();
    dirty = true;
  });
});
const initialRecon = q.get('recon');
if (initialRecon) /** @type {HTMLSelectElement} */ ($('recon')).value = initialRecon;

// Files: the picker and drag and drop.
/**
 * Opens the asset among `files` (a .glb, .gltf or .hce); a .gltf's external buffers are looked
 * up among the other files by name.
 * @param {FileList | undefined | null} files
 */
function openFiles(files) {
  const list = Array.from(files ?? []);
  const main = list.find((f) => /\.(glb|gltf|hce)$/i.test(f.name)) ?? list[0];
  if (!main) return;
  guarded(async () => open(new Uint8Array(await main.arrayBuffer()), main.name, async (uri) => {
    const name = decodeURIComponent(uri.split('/').pop() ?? uri);
    const file = list.find((f) => f.name === name);
    if (!file) throw new Error(`drop or pick '${name}' together with ${main.name}`);
    return new Uint8Array(await file.arrayBuffer());
  }));
}

$('file').addEventListener('change', (e) => openFiles(/** @type {HTMLInputElement} */ (e.target).files));
const viewEl = $('view');
viewEl.addEventListener('dragover', (e) => {
  e.preventDefault();
  viewEl.classList.add('dragging');
});
viewEl.addEventListener('dragleave', () => viewEl.classList.remove('dragging'));
viewEl.addEventListener('drop', (e) => {
  e.preventDefault();
  viewEl.classList.remove('dragging');
  openFiles(e.dataTransfer?.files);
});
window.addEventListener('unhandledrejection', (e) => {
  e.preventDefault();
  showError(e.reason);
});

start().catch((e) => showError(e, 'could not start the viewer'));
