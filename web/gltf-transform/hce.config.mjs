// glTF Transform CLI configuration that keeps hce's baked lighting:
//
//   gltf-transform optimize in.glb out.glb --config node_modules/@hce/gltf-transform/hce.config.mjs
//
// The CLI replaces its extension list with this one, so it lists every extension the CLI knows
// as well as EXT_hce_baked_lighting.
import { ALL_EXTENSIONS } from '@gltf-transform/extensions';
import { HCEBakedLighting } from '@hce/gltf-transform';

export default {
  extensions: [...ALL_EXTENSIONS, HCEBakedLighting],
};
