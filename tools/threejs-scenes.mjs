// What three.js shows of a glTF file: loads it with GLTFLoader (node, no browser; textures taken out
// first, node has no image decoder) and prints, as JSON, the default scene's index and, per scene, its
// name and the meshes it draws (name, skinned, vertices, visible). Used for docs/export.md; the test
// suite does not need it. Needs `npm install three` beside it.
//   node threejs-scenes.mjs FILE.glb
import fs from 'node:fs';
import { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';

function withoutTextures(bytes) {
  const jsonLen = bytes.readUInt32LE(12);
  const json = JSON.parse(bytes.subarray(20, 20 + jsonLen).toString('utf8'));
  delete json.images;
  delete json.textures;
  delete json.samplers;
  for (const m of json.materials || []) delete m.pbrMetallicRoughness?.baseColorTexture;
  let text = Buffer.from(JSON.stringify(json), 'utf8');
  text = Buffer.concat([text, Buffer.alloc((4 - (text.length % 4)) % 4, 0x20)]);
  const rest = bytes.subarray(20 + jsonLen);
  const head = Buffer.alloc(20);
  head.write('glTF', 0, 'ascii');
  head.writeUInt32LE(2, 4);
  head.writeUInt32LE(20 + text.length + rest.length, 8);
  head.writeUInt32LE(text.length, 12);
  head.write('JSON', 16, 'ascii');
  return Buffer.concat([head, text, rest]);
}

const glb = withoutTextures(fs.readFileSync(process.argv[2]));
const ab = glb.buffer.slice(glb.byteOffset, glb.byteOffset + glb.byteLength);
const gltf = await new Promise((ok, fail) => new GLTFLoader().parse(ab, '', ok, fail));
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
