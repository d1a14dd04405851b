export { BakedLighting, BakedPrimitive, EXT_HCE_BAKED_LIGHTING, HCEBakedLighting } from './extension.js';
export { type ContainerObject, type ContainerSummary, readContainerSummary } from './container.js';
export { geometryHash, triangleCount } from './hash.js';
