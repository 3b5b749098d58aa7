// What three.js shows of a glTF file: loads it with GLTFLoader (node, no browser; threejs-load.mjs)
// and prints, as JSON, the default scene's index and, per scene, its
// name and the meshes it draws (name, skinned, vertices, visible). Used for docs/export.md; the test
// suite does not need it. Needs `npm install three` beside it.
//   node threejs-scenes.mjs FILE.glb
import { loadGlb } from './threejs-load.mjs';

const gltf = await loadGlb(process.argv[2]);
const scenes = gltf.scenes.map((s) => {
  const meshes = [];
  s.traverse((o) => {
    if (o.isMesh) {
      meshes.push({
        name: o.name,
        skinned: !!o.isSkinnedMesh,
        vertices: o.geometry.attributes.position.count,
        visible: o.visible,
      });
    }
  });
  return { name: s.name, meshes };
});
console.log(JSON.stringify({ scene: gltf.scenes.indexOf(gltf.scene), animations: gltf.animations.length, scenes }));
