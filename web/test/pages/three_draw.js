// Test (three.js drawing): the baked file at `url` loaded with GLTFLoader and the hce plugin on
// the renderer `make` builds, drawn through the file's first camera into a float render target
// of `width` × `height`, read back and tone-mapped as present.wgsl does (exposure 0, the ACES
// fit, sRGB): RGBA bytes, rows top to bottom. 'three' is whichever build the page's import map
// names (three.webgpu.js for WebGPURenderer, three.module.js for WebGLRenderer).
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { HceGLTFPlugin } from '../../src/three/HceGLTFPlugin.js';
import { toneMap } from './tone_map.js';

/**
 * @param {string} url
 * @param {number} level
 * @param {(three: typeof THREE) => any} make
 * @param {number} width
 * @param {number} height
 */
export async function draw(url, level, make, width, height) {
  try {
    const renderer = make(THREE);
    if (renderer.init) await renderer.init();
    const runtime = await HceGLTFPlugin.runtime(renderer, { wgslBase: new URL('/runtime/src/gpu/', location.href) });
    /** @type {any} */
    let plugin;
    const loader = new GLTFLoader();
    loader.register((parser) => (plugin = new HceGLTFPlugin(parser, runtime, { level })));
    const t0 = performance.now();
    const gltf = await loader.loadAsync(url);
    const loadMs = performance.now() - t0;
    const camera = /** @type {THREE.PerspectiveCamera} */ (gltf.cameras[0]);
    if (!camera) throw new Error(`${url} has no camera`);
    camera.aspect = width / height;
    camera.updateProjectionMatrix();
    const webgl = renderer.isWebGLRenderer === true;
    const target = webgl
      ? new THREE.WebGLRenderTarget(width, height, { type: THREE.FloatType })
      : new THREE.RenderTarget(width, height, { type: THREE.FloatType });
    renderer.setRenderTarget(target);
    renderer.render(gltf.scene, camera);
    /** @type {Float32Array} */
    let linear;
    if (webgl) {
      linear = new Float32Array(4 * width * height);
      renderer.readRenderTargetPixels(target, 0, 0, width, height, linear);
    } else {
      linear = await renderer.readRenderTargetPixelsAsync(target, 0, 0, width, height);
    }
    // WebGL reads rows bottom to top; WebGPU top to bottom.
    const bottomUp = webgl || renderer.backend?.isWebGLBackend === true;
    const out = new Uint8ClampedArray(4 * width * height);
    for (let y = 0; y < height; y++) {
      const src = bottomUp ? height - 1 - y : y;
      for (let x = 0; x < width; x++) {
        const i = 4 * (src * width + x);
        const o = 4 * (y * width + x);
        for (let k = 0; k < 3; k++) out[o + k] = toneMap(linear[i + k]);
        out[o + 3] = 255;
      }
    }
    const canvas = document.createElement('canvas');
    canvas.width = width;
    canvas.height = height;
    const cx = /** @type {CanvasRenderingContext2D} */ (canvas.getContext('2d'));
    cx.putImageData(new ImageData(out, width, height), 0, 0);
    let meshes = 0;
    gltf.scene.traverse((/** @type {any} */ o) => { if (o.isMesh && o.geometry.userData.hce) meshes += 1; });
    return {
      ok: true,
      pixels: Array.from(out),
      png: canvas.toDataURL('image/png'),
      report: plugin.report,
      meshes,
      loadMs,
      backend: webgl ? 'WebGLRenderer' : renderer.backend?.isWebGPUBackend ? 'WebGPU' : 'WebGL2',
    };
  } catch (e) {
    return { ok: false, error: String((e && /** @type {any} */ (e).stack) || e) };
  }
}
