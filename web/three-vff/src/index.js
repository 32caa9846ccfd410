// @vff/three - visibility fields (.vff) in three.js. Each file one concept:
//   VffField (field.js)         a .vff as textures and uniforms for the GLSL ES query
//   VffGLTFPlugin (gltf_plugin.js)  GLTFLoader reads VFF_visibility_field
//   VffOcclusion (occlusion.js) AO and soft shadows of moving field objects on the scene's surfaces
//   decodeInWorker (worker.js)  decoding off the main thread, with progress
//   createVffImpostor (impostor.js) a field's object drawn from the field itself
export { VffField, FIELD_GLSL } from './field.js';
export { VffGLTFPlugin } from './gltf_plugin.js';
export { VffOcclusion } from './occlusion.js';
export { decodeInWorker } from './worker.js';
export { decodeVff } from './decode.js';
export { VffImpostorMaterial, createVffImpostor } from './impostor.js';
