// A three.js app built by Vite with hce from npm: `hce-web/three` by bare specifier, its kernels'
// WGSL and hce.wasm emitted into the bundle by Vite (the package reaches them through
// import.meta.url), no wgslBase. Opens ?url= (a baked .glb) and draws it through its camera,
// with the baked light as linear vertex colours under ACES tone mapping.
import * as THREE from 'three/webgpu';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { HceGLTFPlugin } from 'hce-web/three';

const info = document.getElementById('info');
const state = { ok: false, error: null, path: '', report: [], frames: 0 };
window.hceExample = state;
try {
  const renderer = new THREE.WebGPURenderer({ antialias: true });
  renderer.setSize(640, 480);
  renderer.toneMapping = THREE.ACESFilmicToneMapping;
  document.body.append(renderer.domElement);
  await renderer.init();
  const kernels = await HceGLTFPlugin.runtime(renderer, {
    progress: (done, total) => { info.textContent = `compiling the hce kernels: ${done} of ${total}`; },
  });
  let plugin;
  const loader = new GLTFLoader();
  loader.register((parser) => (plugin = new HceGLTFPlugin(parser, kernels, { level: 2 })));
  const url = new URLSearchParams(location.search).get('url');
  if (!url) throw new Error('open this page with ?url=BAKED.glb');
  const gltf = await loader.loadAsync(url);
  const scene = new THREE.Scene();
  scene.add(gltf.scene);
  const camera = gltf.cameras[0] ?? new THREE.PerspectiveCamera(45, 640 / 480, 0.01, 100);
  if (camera.isPerspectiveCamera) camera.aspect = 640 / 480;
  camera.updateProjectionMatrix();
  await renderer.renderAsync(scene, camera);
  state.frames += 1;
  state.report = plugin.report;
  state.path = kernels.path ?? 'gpu';
  state.ok = true;
  info.textContent = `${plugin.report.length} objects refined (${state.path})`;
} catch (e) {
  state.error = String(e && e.stack || e);
  info.textContent = `error: ${e}`;
}
