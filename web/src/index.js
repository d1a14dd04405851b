// hce in the browser: the public API (web/README.md).
export { HceError } from './errors.js';
export { loadAsset, objectTables, geometryHash, coarseRangeIndices, MAX_LOOP_LEVEL, MAX_PATH_LEVEL } from './native.js';
export { fetchWgsl, importOrder, kernelFiles, KernelSources, loadWgsl, packagedWgsl, WgShape, WGSL_ROOTS } from './wgsl.js';
export { everyKernel } from './pipelines.js';
export { Kernels, destroyRefined, destroyUploaded } from './kernels.js';
export { HceScene, Renderer, FLAT_MAX_LEVEL, FLAT_MAX_TRIANGLES, flatLevel } from './scene.js';
export { chooseLevel, objectLevel, resolveCamera, autoCamera, autoSceneCamera, viewProjection, assetBounds, DEFAULT_LOD } from './view.js';
export { requestDevice } from './device.js';

/**
 * Everything a page needs, built once: a device (or the caller's), the kernels' pipelines and
 * the renderer.
 * @param {object} options
 * @param {string | URL} [options.wgslBase] the URL of runtime/src/gpu/ (ending in `/`); by
 *   default the kernel sources the npm package ships (`packagedWgsl`)
 * @param {GPUDevice} [options.device] draw on this device (e.g. three.js's) instead of a new one
 * @param {GPUTextureFormat} [options.canvasFormat] build the renderer for this canvas format
 * @param {(done: number, total: number, label: string) => void} [options.progress]
 */
export async function createRuntime(options) {
  const { KernelSources, kernelFiles } = await import('./wgsl.js');
  const { Kernels } = await import('./kernels.js');
  const { Renderer } = await import('./scene.js');
  const { requestDevice } = await import('./device.js');
  const requested = options.device ? null : await requestDevice();
  const device = options.device ?? /** @type {NonNullable<typeof requested>} */ (requested).device;
  const sources = new KernelSources(await kernelFiles(options.wgslBase));
  const kernels = await Kernels.create(device, sources, options.progress);
  let renderer = null;
  if (options.canvasFormat) {
    const presentUrl = new URL('./present.wgsl', import.meta.url);
    const response = await fetch(presentUrl);
    if (!response.ok) throw new Error(`cannot load ${presentUrl}: HTTP ${response.status}`);
    renderer = await Renderer.create(device, sources, await response.text(), options.canvasFormat);
  }
  // The adapter is kept with the device: Chrome cancels a device's pending callbacks
  // ("A valid external Instance reference no longer exists") once its adapter is collected.
  return { adapter: requested?.adapter ?? null, device, sources, kernels, renderer };
}
