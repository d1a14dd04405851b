// Every kernel module the runtime assembles, with its entry points: what the browser compiles
// and what test (a) checks compiles in Chromium's WebGPU with no message.
import { KernelSources, WgShape } from './wgsl.js';

/**
 * @typedef {object} KernelModule
 * @property {string} label
 * @property {string} code the assembled WGSL
 * @property {string[]} compute compute entry points
 * @property {boolean} [render] a render module (vs_main, fs_main)
 */

/**
 * The modules of every kernel: flat, Loop (scratch patch kernel), the workgroup patch
 * kernel at levels 0 to 5 for `ringPoints` (the Rust runtime's variants), decoding, the
 * renderer and the bandwidth reference.
 * @param {KernelSources} sources
 * @param {{ ringPoints?: number, workgroupLimit?: number }} [options]
 * @returns {KernelModule[]}
 */
export function everyKernel(sources, options = {}) {
  const ringPoints = options.ringPoints ?? 24;
  const limit = options.workgroupLimit ?? 16384;
  /** @type {KernelModule[]} */
  const modules = [
    { label: 'flat', code: sources.flat(), compute: ['positions_main', 'faces_main', 'colours_main'] },
    { label: 'loop', code: sources.loop(), compute: ['patch_main', 'faces_main', 'colours_main'] },
  ];
  for (let level = 0; level <= 5; level++) {
    const shape = WgShape.fit(level, ringPoints, limit);
    if (shape === null) continue;
    modules.push({
      label: `loop workgroup ${shape.key()}`,
      code: sources.loopWorkgroup(shape.header()),
      compute: ['patch_wg_main'],
    });
  }
  modules.push(
    { label: 'decode', code: sources.decode(), compute: ['decode_main'] },
    { label: 'fill', code: sources.fill(), compute: ['fill_main'] },
    { label: 'render', code: sources.render(), compute: [], render: true },
  );
  return modules;
}
