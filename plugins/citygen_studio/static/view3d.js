// The selected building in 3D (three.js), loaded on the first selection so the page paints and the editor works
// before three.js (2 MB) is fetched and compiled.
import * as THREE from "three";
import {GLTFLoader} from "./vendor/three/examples/jsm/loaders/GLTFLoader.js";
import {OrbitControls} from "./vendor/three/examples/jsm/controls/OrbitControls.js";

// A view in ``host``: ``show(base64Glb, frame)`` replaces the model (``frame``: aim the camera at it);
// ``onPick(face)`` is told the dressed face (of ``faces()``) under a click that was not a drag.
export function createView(host, faces, onPick, onError) {
  const renderer = new THREE.WebGLRenderer({antialias: true, preserveDrawingBuffer: true});
  renderer.setPixelRatio(window.devicePixelRatio);
  host.appendChild(renderer.domElement);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xdde3ea);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x8d8d80, 2.2));
  const sun = new THREE.DirectionalLight(0xffffff, 2.0);
  sun.position.set(40, 80, 30);
  scene.add(sun);
  const camera = new THREE.PerspectiveCamera(40, 1, 0.1, 5000);
  camera.position.set(30, 25, 40);
  const controls = new OrbitControls(camera, renderer.domElement);
  let model = null, down = null;

  // A click on the building picks the dressed face whose rectangle holds the hit point, nearest along its normal
  // (reveals and balconies stand off the wall plane).
  function pick(event) {
    if (!model) return;
    const rect = renderer.domElement.getBoundingClientRect();
    const pointer = new THREE.Vector2(((event.clientX - rect.left) / rect.width) * 2 - 1,
      -((event.clientY - rect.top) / rect.height) * 2 + 1);
    const raycaster = new THREE.Raycaster();
    raycaster.setFromCamera(pointer, camera);
    const hit = raycaster.intersectObject(model, true)[0];
    if (!hit) return;
    let best = null, bestDistance = 1.5;
    for (const face of faces()) {
      if (!face.layout) continue;
      const d = hit.point.clone().sub(new THREE.Vector3(...face.origin));
      const x = d.dot(new THREE.Vector3(...face.u)), off = Math.abs(d.dot(new THREE.Vector3(...face.normal)));
      if (x >= -0.05 && x <= face.width + 0.05 && d.y >= -0.05 && d.y <= face.height + 0.05 && off < bestDistance) {
        best = face;
        bestDistance = off;
      }
    }
    if (best) onPick(best);
  }
  renderer.domElement.addEventListener("pointerdown", (e) => { down = [e.clientX, e.clientY]; });
  renderer.domElement.addEventListener("pointerup", (e) => {
    if (down && Math.hypot(e.clientX - down[0], e.clientY - down[1]) < 4) pick(e);
  });
  const resize = () => {
    const {clientWidth: w, clientHeight: h} = host;
    renderer.setSize(w, h, false);
    camera.aspect = w / Math.max(h, 1);
    camera.updateProjectionMatrix();
  };
  new ResizeObserver(resize).observe(host);
  resize();
  renderer.setAnimationLoop(() => { controls.update(); renderer.render(scene, camera); });

  function show(base64, frame) {
    const bytes = Uint8Array.from(atob(base64), (c) => c.charCodeAt(0));
    new GLTFLoader().parse(bytes.buffer, "", (gltf) => {
      if (model) scene.remove(model);
      model = gltf.scene;
      scene.add(model);
      if (frame) {
        const box = new THREE.Box3().setFromObject(model);
        const centre = box.getCenter(new THREE.Vector3()), size = box.getSize(new THREE.Vector3()).length();
        controls.target.copy(centre);
        camera.position.copy(centre).add(new THREE.Vector3(0.6, 0.45, 0.8).multiplyScalar(size));
      }
      host.dataset.meshes = String(gltf.scene.getObjectsByProperty("isMesh", true).length);
    }, onError);
  }
  return {show};
}
