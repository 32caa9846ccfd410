// gltf_plugin.js - VffGLTFPlugin: three.js's GLTFLoader reads the glTF extension VFF_visibility_field
// (spec/gltf/VFF_visibility_field/README.md) with the same rules and checks as web/src/gltf_fields.js.
//
//   const loader = new GLTFLoader().register((parser) => new VffGLTFPlugin(parser));
//   const gltf = await loader.loadAsync('scene.glb');
//   gltf.userData.vffFields   // [{mesh, name, field: VffField | null, match, problems}]
//   gltf.userData.vffProblems // every problem of the asset (rule, name, severity, path, message)
//   object.userData.vffField  // on each Mesh/Group made from a glTF mesh with a usable field, at a
//                             // node the field answers for (no skin, mirror, morph, non-similarity)
// The field is in that object's local (mesh) space.
import { LoaderUtils, FileLoader } from 'three';
import { GLTF_FIELD_EXTENSION, readParsedGltfFields } from '../../src/gltf_fields.js';
import { VffField } from './field.js';

export class VffGLTFPlugin {
  /** options.checkGeometry (default true): match each field against the mesh's triangles. */
  constructor(parser, options = {}) {
    this.parser = parser;
    this.name = GLTF_FIELD_EXTENSION;
    this.options = options;
  }

  async afterRoot(result) {
    const parser = this.parser, json = parser.json;
    const body = parser.extensions.KHR_binary_glTF?.body ?? null;
    const resolveUri = (path) => new FileLoader(parser.options.manager).setResponseType('arraybuffer')
      .loadAsync(LoaderUtils.resolveURL(encodeURI(path), parser.options.path ?? ''));
    // Draco and meshopt primitives: the triangles three.js decoded.
    const decodedGeometry = async (m, p) => {
      const obj = await parser.getDependency('mesh', m);
      const meshes = obj.isMesh ? [obj] : obj.children.filter((c) => c.isMesh);
      const g = meshes[p]?.geometry;
      if (!g) return null;
      const pos = g.getAttribute('position');
      const positions = new Float32Array(pos.count * 3);
      for (let i = 0; i < pos.count; ++i) positions.set([pos.getX(i), pos.getY(i), pos.getZ(i)], 3 * i);
      return { positions, indices: g.index ? Uint32Array.from(g.index.array) : null };
    };
    const report = await readParsedGltfFields(
      { json, bin: body ? new Uint8Array(body) : null, glb: !!body },
      { resolveUri, decodedGeometry, checkGeometry: this.options.checkGeometry ?? true });
    const entries = [];
    for (const f of report.fields) {
      const problems = report.problems.filter((p) => p.path.startsWith(`/meshes/${f.mesh}/`) || p.path === `/meshes/${f.mesh}` ||
        f.nodes.some((n) => p.path === `/nodes/${n.node}`));
      let field = null;
      if (f.usable) {
        try {
          field = await VffField.fromBytes(f.bytes, { name: f.meshName || `mesh ${f.mesh}` });
        } catch (e) {
          // readGltfFields already ran every check of the payload; this is a decoder failure.
          problems.push({ rule: 14009, name: 'gltf-payload', severity: 'error', path: f.path, message: String(e?.message ?? e) });
        }
      }
      entries.push({ mesh: f.mesh, name: f.meshName, field, match: f.match, nodes: f.nodes, problems });
    }
    // The object each node made from its glTF mesh: the node's own object, or (a node that also
    // holds a camera) its child of the mesh's kind. parser.associations cannot serve: GLTFLoader
    // keeps only the last loaded scene's there.
    const byMesh = new Map(entries.filter((e) => e.field).map((e) => [e.mesh, e.field]));
    for (const f of report.fields) {
      const field = byMesh.get(f.mesh);
      if (!field) continue;
      const single = (json.meshes[f.mesh].primitives?.length ?? 0) === 1;
      const isMeshObject = (o) => (single ? o.isMesh : o.isGroup && o.children.length > 0 && o.children.every((c) => c.isMesh));
      for (const n of f.nodes) {
        if (!n.answered) continue;
        const node = await parser.getDependency('node', n.node);
        const object = isMeshObject(node) ? node : node.children.find(isMeshObject);
        if (object) object.userData.vffField = field;
      }
    }
    result.userData ??= {};
    result.userData.vffFields = entries;
    result.userData.vffProblems = report.problems;
  }
}
