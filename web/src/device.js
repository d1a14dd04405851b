// The WebGPU device the runtime asks for: WebGPU's default limits except the buffer sizes
// (refined meshes are large), which are raised to what the adapter offers, as the Rust runtime
// does (runtime/src/gpu/context.rs). Storage buffers per stage stay at the default 8.

/**
 * @param {{ powerPreference?: GPUPowerPreference }} [options]
 * @returns {Promise<{ adapter: GPUAdapter, device: GPUDevice }>}
 */
export async function requestDevice(options = {}) {
  if (typeof navigator === 'undefined' || !navigator.gpu) {
    throw new Error('this browser has no WebGPU (navigator.gpu); use a recent Chrome, Edge or Firefox, or start Chromium with --enable-unsafe-webgpu');
  }
  const adapter = await adapterWithRetries(options.powerPreference ?? 'high-performance');
  if (!adapter) throw new Error('WebGPU gives no adapter on this machine');
  const device = await adapter.requestDevice({
    label: 'hce',
    requiredLimits: {
      maxStorageBufferBindingSize: adapter.limits.maxStorageBufferBindingSize,
      maxBufferSize: adapter.limits.maxBufferSize,
    },
  });
  return { adapter, device };
}

/**
 * The adapter, asked for up to four times over about 1.5 s: while its GPU process restarts (after
 * a device was lost, as headless Chromium on SwiftShader loses the viewer's canvas probe),
 * Chromium answers `null` for a moment, and a page opened then said there was no adapter.
 * @param {GPUPowerPreference} powerPreference
 * @returns {Promise<GPUAdapter | null>}
 */
async function adapterWithRetries(powerPreference) {
  for (let attempt = 0; attempt < 4; attempt += 1) {
    if (attempt > 0) await new Promise((resolve) => setTimeout(resolve, 250 * attempt));
    const adapter = await navigator.gpu.requestAdapter({ powerPreference });
    if (adapter) return adapter;
  }
  return null;
}
