// The viewer's path without WebGPU: a loaded asset refined on the CPU in hce.wasm (the Rust of
// `hce subdivide`, cpu_refine.js) at the levels HceScene chooses (scene.js `sceneLevels`), and
// drawn with WebGL2 as render.wgsl draws it (no lighting: the colours are baked radiance; both
// sides; the nearest surface), then exposure, the ACES fit and sRGB encoding of present.wgsl.
// Those are applied per fragment here: with one sample per pixel and no blending, that is the
// same as tone-mapping the linear image afterwards, and it needs no float render target.
import { multiply } from './math.js';
import { DEFAULT_LOD, viewProjection } from './view.js';
import { DEFAULT_TRIANGLE_BUDGET, sceneLevels } from './scene.js';
import { cpuLevel, refineCpu } from './cpu_refine.js';

/**
 * @typedef {import('./native.js').Asset} Asset
 * @typedef {import('./native.js').Reconstruction} Reconstruction
 * @typedef {import('./view.js').Camera} Camera
 * @typedef {{ vao: WebGLVertexArrayObject, buffers: WebGLBuffer[], triangleCount: number }} GlMesh
 * @typedef {{ source: import('./native.js').AssetObject, forced: number | null, level: number, refined: GlMesh | null, refineMs: number }} GlObject
 */

const VERTEX = `#version 300 es
uniform mat4 viewProj;
in vec3 position;
in vec4 colour;
out vec3 linear;
void main() {
  gl_Position = viewProj * vec4(position, 1.0);
  linear = colour.rgb;
}`;

// present.wgsl's fs_present, per fragment.
const FRAGMENT = `#version 300 es
precision highp float;
uniform float exposure;
in vec3 linear;
out vec4 srgb;
void main() {
  vec3 x = max(linear, vec3(0.0)) * exposure;
  vec3 y = clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), vec3(0.0), vec3(1.0));
  vec3 s = mix(1.055 * pow(y, vec3(1.0 / 2.4)) - 0.055, 12.92 * y, lessThanEqual(y, vec3(0.0031308)));
  srgb = vec4(s, 1.0);
}`;

/**
 * The WebGL2 context of `canvas` for the viewer, or null where the browser has none.
 * @param {HTMLCanvasElement} canvas
 */
export function webgl2Context(canvas) {
  // preserveDrawingBuffer: a frame stays readable (screenshots, tests) after it is shown.
  return canvas.getContext('webgl2', { antialias: false, depth: true, alpha: false, preserveDrawingBuffer: true });
}

/** A scene refined on the CPU and drawn with WebGL2; the viewer uses it as it uses HceScene. */
export class GlScene {
  /**
   * @param {WebGL2RenderingContext} gl
   * @param {Asset} asset
   * @param {{ reconstruction?: Reconstruction, triangleBudget?: number, flatRefinement?: import('./native.js').FlatRefinement }} [options]
   *   as HceScene's
   */
  constructor(gl, asset, options = {}) {
    this.gl = gl;
    this.asset = asset;
    this.reconstruction = options.reconstruction ?? 'smooth';
    this.flatRefinement = options.flatRefinement ?? 'adaptive';
    this.triangleBudget = options.triangleBudget ?? DEFAULT_TRIANGLE_BUDGET;
    /** @type {GlObject[]} */
    this.objects = asset.objects.map((source) => ({ source, forced: null, level: -1, refined: null, refineMs: 0 }));
    this.program = program(gl);
  }

  /** Nothing to upload before refining: the CPU reads the objects as they are. */
  upload() {}

  /** @param {Reconstruction} reconstruction */
  setReconstruction(reconstruction) {
    if (reconstruction === this.reconstruction) return;
    this.reconstruction = reconstruction;
    for (const o of this.objects) o.level = -1;
  }

  /**
   * As HceScene.levelsFor, with each level the one the CPU refines to (cpu_refine.js `cpuLevel`).
   * @param {Camera} camera
   * @param {number} viewportHeight
   */
  levelsFor(camera, viewportHeight) {
    const levels = sceneLevels(this.objects.map((o) => ({ source: o.source, forced: o.forced, treeDepth: o.source.object.treeDepth, triangles: this.adaptiveTriangles(o) })), camera, viewportHeight, DEFAULT_LOD, this.triangleBudget);
    return levels.map((l, i) => (l < 0 ? l : cpuLevel(this.objects[i].source.object, l)));
  }

  /**
   * The triangles an adaptive flat object draws whatever its level (SPEC.md F.7.1), null for
   * the others. Known once refined; before that, its coarse triangle count, the fewest it can
   * draw (the CPU path has no tables built ahead of its refinement).
   * @param {GlObject} o
   */
  adaptiveTriangles(o) {
    if (o.source.object.kind !== 'flat' || this.flatRefinement !== 'adaptive') return null;
    return o.refined?.triangleCount ?? o.source.object.records.length / 4;
  }

  /**
   * Refines (on this thread) every object whose level changed and uploads it.
   * @param {number[]} levels
   */
  async refineTo(levels) {
    const gl = this.gl;
    for (let i = 0; i < this.objects.length; i++) {
      const o = this.objects[i];
      if (levels[i] < 0 || (levels[i] === o.level && o.refined !== null)) continue;
      const mesh = refineCpu(o.source.object, levels[i], this.reconstruction, this.flatRefinement);
      if (o.refined) release(gl, o.refined);
      o.refined = upload(gl, mesh);
      o.refineMs = mesh.ms;
      o.level = levels[i];
    }
  }

  /** Triangles drawn (every instance). */
  drawnTriangles() {
    return this.objects.reduce((s, o) => s + (o.refined ? o.refined.triangleCount * o.source.instances.length : 0), 0);
  }

  /**
   * Draws every instance through `camera` into the canvas.
   * @param {Camera} camera
   * @param {import('./math.js').Bounds} bounds the near and far planes are set around these
   * @param {number} exposureEv
   */
  render(camera, bounds, exposureEv = 0) {
    const gl = this.gl;
    const { width, height } = gl.canvas;
    gl.viewport(0, 0, width, height);
    gl.clearColor(0, 0, 0, 1);
    gl.clearDepth(1);
    gl.enable(gl.DEPTH_TEST);
    gl.depthFunc(gl.LESS);
    gl.disable(gl.CULL_FACE);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.useProgram(this.program);
    gl.uniform1f(gl.getUniformLocation(this.program, 'exposure'), 2 ** exposureEv);
    const at = gl.getUniformLocation(this.program, 'viewProj');
    const viewProj = viewProjection(camera, bounds, width / height);
    for (const o of this.objects) {
      if (!o.refined) continue;
      gl.bindVertexArray(o.refined.vao);
      for (const inst of o.source.instances) {
        gl.uniformMatrix4fv(at, false, glClip(multiply(viewProj, inst.transform)));
        gl.drawElements(gl.TRIANGLES, 3 * o.refined.triangleCount, gl.UNSIGNED_INT, 0);
      }
    }
    gl.bindVertexArray(null);
  }

  /** Frees every buffer. */
  destroy() {
    for (const o of this.objects) if (o.refined) release(this.gl, o.refined);
    this.gl.deleteProgram(this.program);
  }
}

/**
 * A WebGPU clip-space matrix (depth 0 to w) as WebGL's (-w to w): z' = 2z - w, so that the
 * near plane clips where it clips on WebGPU.
 * @param {number[]} m column-major
 */
function glClip(m) {
  const out = Float32Array.from(m);
  for (let c = 0; c < 4; c++) out[4 * c + 2] = 2 * m[4 * c + 2] - m[4 * c + 3];
  return out;
}

/** @param {WebGL2RenderingContext} gl */
function program(gl) {
  const shader = (/** @type {number} */ type, /** @type {string} */ source) => {
    const s = /** @type {WebGLShader} */ (gl.createShader(type));
    gl.shaderSource(s, source);
    gl.compileShader(s);
    if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(`WebGL2 shader: ${gl.getShaderInfoLog(s)}`);
    return s;
  };
  const p = /** @type {WebGLProgram} */ (gl.createProgram());
  gl.attachShader(p, shader(gl.VERTEX_SHADER, VERTEX));
  gl.attachShader(p, shader(gl.FRAGMENT_SHADER, FRAGMENT));
  gl.bindAttribLocation(p, 0, 'position');
  gl.bindAttribLocation(p, 1, 'colour');
  gl.linkProgram(p);
  if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error(`WebGL2 program: ${gl.getProgramInfoLog(p)}`);
  return p;
}

/**
 * @param {WebGL2RenderingContext} gl
 * @param {import('./cpu_refine.js').CpuMesh} mesh
 * @returns {GlMesh}
 */
function upload(gl, mesh) {
  const vao = /** @type {WebGLVertexArrayObject} */ (gl.createVertexArray());
  gl.bindVertexArray(vao);
  const buffer = (/** @type {number} */ target, /** @type {ArrayBufferView} */ data) => {
    const b = /** @type {WebGLBuffer} */ (gl.createBuffer());
    gl.bindBuffer(target, b);
    gl.bufferData(target, data, gl.STATIC_DRAW);
    return b;
  };
  const positions = buffer(gl.ARRAY_BUFFER, mesh.positions);
  gl.enableVertexAttribArray(0);
  gl.vertexAttribPointer(0, 3, gl.FLOAT, false, 12, 0);
  const colours = buffer(gl.ARRAY_BUFFER, mesh.colours);
  gl.enableVertexAttribArray(1);
  gl.vertexAttribPointer(1, 4, gl.FLOAT, false, 16, 0);
  const indices = buffer(gl.ELEMENT_ARRAY_BUFFER, mesh.indices);
  gl.bindVertexArray(null);
  return { vao, buffers: [positions, colours, indices], triangleCount: mesh.indices.length / 3 };
}

/** @param {WebGL2RenderingContext} gl @param {GlMesh} mesh */
function release(gl, mesh) {
  gl.deleteVertexArray(mesh.vao);
  for (const b of mesh.buffers) gl.deleteBuffer(b);
}
