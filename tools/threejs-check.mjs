// Plays a `sinew export` GLB in three.js (node, no browser) and compares the skinned vertices with
// `sinew bake --format pc2` of the same file and clip, at the bake's own frame times (so at any frame
// rate: bake with `--fps 30` to check what a 30 fps viewer shows of a 24 fps clip). Also compares the
// rest pose (no animation playing) with the glTF's own bind-pose vertices skinned by three.js's
// bind pose. Prints the largest distance relative to the bounding-box diagonal of the bind pose.
// Used for docs/export.md; the test suite does not need it. Needs `npm install three` beside it.
//   node threejs-check.mjs EXPORT.glb BAKE.pc2 CLIP
import fs from 'node:fs';
import * as THREE from 'three';
import { loadGlb } from './threejs-load.mjs';

const [glbPath, pc2Path, clipName, fpsArg] = process.argv.slice(2);
const fps = Number(fpsArg);
// Textures are left out (threejs-load.mjs): poses and skinning do not depend on them.
const gltf = await loadGlb(glbPath);

// PC2: "POINTCACHE2\0", version, points, start frame (f32), sample step (f32), samples.
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
const duration = gltf.parser.json.extras.sinew.clips.find((c) => c.name === clipName).duration;

const box = new THREE.Box3().setFromBufferAttribute(mesh.geometry.attributes.position);
const diagonal = box.max.distanceTo(box.min);
const p = new THREE.Vector3();

const mixer = new THREE.AnimationMixer(scene);
const action = mixer.clipAction(clip);
action.setLoop(THREE.LoopOnce, 1);
action.clampWhenFinished = true;
action.play();
let worst = 0;
let worstFrame = 0;
for (let f = 0; f < frames; f++) {
  // The bake's frame rule: frame i at i / fps (f64, rounded to f32), the last exactly at the duration.
  const t = f + 1 === frames && f > 0 ? duration : Math.fround(f / fps);
  mixer.setTime(t);
  scene.updateMatrixWorld(true);
  mesh.skeleton.update();
  for (let v = 0; v < n; v++) {
    mesh.getVertexPosition(v, p);
    p.applyMatrix4(mesh.matrixWorld);
    const d = Math.hypot(p.x - baked(f, v, 0), p.y - baked(f, v, 1), p.z - baked(f, v, 2));
    if (d > worst) { worst = d; worstFrame = f; }
  }
}
console.log(`${glbPath} ${clipName}: ${frames} frames at ${fps} fps x ${n} vertices, max distance ${(worst / diagonal).toExponential(2)} of the diagonal ${diagonal.toFixed(4)} (frame ${worstFrame})`);
