// field_three.js - a decoded field (decode.js's result) as three.js resources for ShaderMaterials
// that include the GLSL ES query: the distance (and normal) slices as integer DataArrayTexture (or
// Data3DTexture), the positions table as an RGBA32F DataTexture, and the field block as a struct
// uniform (the query reads it through VFF_FIELD). The object has the shape impostor.js expects:
// {uniforms, defines, glsl, center, radius, dispose()}.
import * as THREE from 'three';
import { FIELD_STRUCT, blockValue, specialisedGlsl } from '../../three-vff/src/field.js';
import { VFF_QUERY_GLSL_ES } from '../vff_query_es.js';

const FORMATS = {
  R8UI: [THREE.RedIntegerFormat, THREE.UnsignedByteType],
  R16UI: [THREE.RedIntegerFormat, THREE.UnsignedShortType],
  RG16I: [THREE.RGIntegerFormat, THREE.ShortType],
};

function sliceTexture(plane, is3d) {
  const t = is3d ? new THREE.Data3DTexture(plane.data, plane.width, plane.height, plane.depth)
    : new THREE.DataArrayTexture(plane.data, plane.width, plane.height, plane.depth);
  [t.format, t.type] = FORMATS[plane.format];
  t.internalFormat = plane.format;
  t.minFilter = t.magFilter = THREE.NearestFilter;
  t.generateMipmaps = false;
  t.unpackAlignment = 1;
  t.needsUpdate = true;
  return t;
}

/** Makes the textures and uniforms of a decoded result's `gpu` part. */
export function fieldResources(result) {
  const g = result.gpu;
  const maps = sliceTexture(g.distance, g.is3d);
  const normals = g.normal ? sliceTexture(g.normal, g.is3d) : null;
  const vec4s = g.table.length / 4, pw = Math.max(1, Math.min(vec4s, 2048)), ph = Math.max(1, Math.ceil(vec4s / pw));
  const padded = new Float32Array(pw * ph * 4);
  padded.set(g.table);
  const positions = new THREE.DataTexture(padded, pw, ph, THREE.RGBAFormat, THREE.FloatType);
  positions.minFilter = positions.magFilter = THREE.NearestFilter;
  positions.generateMipmaps = false;
  positions.needsUpdate = true;
  const defines = { VFF_POSITIONS_WIDTH: String(pw) };
  if (g.is3d) defines.VFF_MAPS_3D = '';
  if (!normals) defines.VFF_NO_NORMALS = '';
  const uniforms = {
    vffField: { value: blockValue(g.block) },
    vffMaps: { value: maps },
    vffPositionsTex: { value: positions },
    ...(normals ? { vffNormals: { value: normals } } : {}),
  };
  return {
    uniforms, defines, glsl: specialisedGlsl(uniforms.vffField.value, `${FIELD_STRUCT}\n${VFF_QUERY_GLSL_ES}`),
    center: new THREE.Vector3(...result.field.center), radius: result.field.radius,
    source: g,  // the plain arrays, for the WebGPU ground (webgpu_ground.js)
    dispose() { maps.dispose(); normals?.dispose(); positions.dispose(); },
  };
}
