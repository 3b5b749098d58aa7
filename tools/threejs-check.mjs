// Plays a `sinew export` GLB in three.js (node, no browser) and compares the skinned vertices of
// every frame with `sinew bake --format pc2` of the same file and clip: prints the largest distance
// relative to the bounding-box diagonal of the bind pose. Used for docs/export.md; the test suite
// does not need it. Needs `npm install three` beside it.
//   node threejs-check.mjs EXPORT.glb BAKE.pc2 CLIP
import fs from 'node:fs';
import * as THREE from 'three';
import { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';

const [glbPath, pc2Path, clipName] = process.argv.slice(2);
const glb = fs.readFileSync(glbPath);
const ab = glb.buffer.slice(glb.byteOffset, glb.byteOffset + glb.byteLength);
const gltf = await new Promise((ok, fail) => new GLTFLoader().parse(ab, '', ok, fail));

const pc2 = fs.readFileSync(pc2Path);
const dv = new DataView(pc2.buffer, pc2.byteOffset, pc2.byteLength);
const points = dv.getInt32(16, true);
const frames = dv.getInt32(28, true);
const baked = (f, v, k) => dv.getFloat32(32 + ((f * points + v) * 3 + k) * 4, true);

const scene = gltf.scene;
let mesh = null;
scene.traverse((o) => { if (!mesh && o.isSkinnedMesh) mesh = o; });
if (!mesh) throw new Error('no skinned mesh');
const n = mesh.geometry.attributes.position.count;
if (n !== points) throw new Error(`vertices: glTF ${n}, pc2 ${points}`);
const clip = gltf.animations.find((a) => a.name === clipName);
if (!clip) throw new Error(`no animation ${clipName}`);
const times = clip.tracks[0].times;
if (times.length !== frames) throw new Error(`frames: glTF ${times.length}, pc2 ${frames}`);

const box = new THREE.Box3().setFromBufferAttribute(mesh.geometry.attributes.position);
const diagonal = box.max.distanceTo(box.min);
const mixer = new THREE.AnimationMixer(scene);
const action = mixer.clipAction(clip);
action.setLoop(THREE.LoopOnce, 1);
action.clampWhenFinished = true;
action.play();
let worst = 0;
const p = new THREE.Vector3();
for (let f = 0; f < frames; f++) {
  mixer.setTime(times[f]);
  scene.updateMatrixWorld(true);
  mesh.skeleton.update();
  for (let v = 0; v < n; v++) {
    mesh.getVertexPosition(v, p);
    p.applyMatrix4(mesh.matrixWorld);
    const d = Math.hypot(p.x - baked(f, v, 0), p.y - baked(f, v, 1), p.z - baked(f, v, 2));
    worst = Math.max(worst, d);
  }
}
console.log(`${glbPath} ${clipName}: ${frames} frames x ${n} vertices, max distance ${worst.toExponential(3)} = ${(worst / diagonal).toExponential(3)} of the diagonal ${diagonal.toFixed(4)}`);
