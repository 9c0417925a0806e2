// The viewer of rfta-view's pages: reads the scene (JSON, arrays in base64) and draws it with
// three.js. Sets document.body.dataset.ready once the first frame is drawn, and shows any error
// on the page.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const fail = (e) => {
  document.getElementById('error').textContent = 'could not draw the scene: ' + e;
  document.body.dataset.ready = 'error';
};

try {
  const scene = JSON.parse(document.getElementById('scene').textContent);
  const bytes = (b64) => Uint8Array.from(atob(b64), (c) => c.charCodeAt(0));
  const floats = (b64) => new Float32Array(bytes(b64).buffer);
  const ints = (b64) => new Uint32Array(bytes(b64).buffer);
  const color = (c) => new THREE.Color(c[0] / 255, c[1] / 255, c[2] / 255).convertSRGBToLinear();

  const view = document.getElementById('view');
  const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio);
  renderer.setClearColor(0xffffff);
  view.appendChild(renderer.domElement);
  const world = new THREE.Scene();
  world.add(new THREE.HemisphereLight(0xffffff, 0x445566, 2.0));
  const sun = new THREE.DirectionalLight(0xffffff, 1.5);
  world.add(sun);

  const box = new THREE.Box3();
  const materials = [];
  const list = document.getElementById('layers');
  const toggle = (name, object, visible, swatch) => {
    object.visible = visible;
    const label = document.createElement('label');
    const input = document.createElement('input');
    input.type = 'checkbox';
    input.checked = visible;
    input.onchange = () => { object.visible = input.checked; draw(); };
    label.appendChild(input);
    if (swatch) {
      const s = document.createElement('span');
      s.className = 'swatch';
      s.style.background = `rgb(${swatch[0]},${swatch[1]},${swatch[2]})`;
      label.appendChild(s);
    }
    label.appendChild(document.createTextNode(' ' + name));
    list.appendChild(label);
  };

  for (const layer of scene.layers) {
    const positions = floats(layer.positions);
    const faces = ints(layer.faces);
    const classes = bytes(layer.classes);
    // Unshared vertices, so that each face takes its class's colour and a flat normal.
    const n = faces.length;
    const p = new Float32Array(n * 3);
    const c = new Float32Array(n * 3);
    for (let f = 0; f < n / 3; f++) {
      const rgb = color(scene.classes[classes.length ? classes[f] : 0].color);
      for (let k = 0; k < 3; k++) {
        const v = faces[3 * f + k];
        p.set(positions.subarray(3 * v, 3 * v + 3), 9 * f + 3 * k);
        c.set([rgb.r, rgb.g, rgb.b], 9 * f + 3 * k);
      }
    }
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(p, 3));
    geometry.setAttribute('color', new THREE.BufferAttribute(c, 3));
    geometry.computeVertexNormals();
    const material = new THREE.MeshStandardMaterial({
      vertexColors: true, flatShading: true, side: THREE.DoubleSide, roughness: 0.8,
      polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1,
    });
    materials.push(material);
    const mesh = new THREE.Mesh(geometry, material);
    world.add(mesh);
    if (layer.visible) box.expandByObject(mesh);
    toggle(`${layer.name} (${n / 3} faces)`, mesh, layer.visible);
  }
  if (box.isEmpty()) box.setFromCenterAndSize(new THREE.Vector3(), new THREE.Vector3(1, 1, 1));
  const size = box.getSize(new THREE.Vector3()).length();
  const centre = box.getCenter(new THREE.Vector3());

  for (const m of scene.marks) {
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(floats(m.positions), 3));
    const material = new THREE.PointsMaterial({ color: color(m.color), size: size / 50, depthTest: false });
    const points = new THREE.Points(geometry, material);
    points.renderOrder = 2;
    world.add(points);
    toggle(`${m.name}: ${m.count}`, points, m.count > 0, m.color);
  }
  for (const cv of scene.curves) {
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(floats(cv.segments), 3));
    const material = new THREE.LineBasicMaterial({ color: color(cv.color), depthTest: false });
    const lines = new THREE.LineSegments(geometry, material);
    lines.renderOrder = 3;
    world.add(lines);
    toggle(`${cv.name}: ${cv.count}`, lines, cv.count > 0, cv.color);
  }
  for (const cl of scene.classes) {
    const row = document.createElement('div');
    row.innerHTML = `<span class="swatch" style="background: rgb(${cl.color.join(',')})"></span>`;
    row.appendChild(document.createTextNode(cl.name));
    list.appendChild(row);
  }

  const camera = new THREE.PerspectiveCamera(35, 1, size / 1000, size * 100);
  camera.position.copy(centre).add(new THREE.Vector3(0.9, 0.6, 1.4).normalize().multiplyScalar(1.9 * size));
  const controls = new OrbitControls(camera, renderer.domElement);
  controls.target.copy(centre);
  controls.addEventListener('change', () => draw());
  document.getElementById('wireframe').onchange = (e) => {
    for (const m of materials) m.wireframe = e.target.checked;
    draw();
  };
  // See through the surface to what it encloses: on when a layer has a cavity or an island.
  const through = document.getElementById('through');
  const seeThrough = (on) => {
    for (const m of materials) { m.transparent = on; m.opacity = on ? 0.35 : 1; m.depthWrite = !on; m.needsUpdate = true; }
    draw();
  };
  through.checked = scene.layers.some((l) => bytes(l.classes).some((c) => c > 0));
  through.onchange = (e) => seeThrough(e.target.checked);
  seeThrough(through.checked);

  function draw() {
    const w = view.clientWidth, h = view.clientHeight;
    renderer.setSize(w, h, false);
    renderer.domElement.style.width = '100%';
    renderer.domElement.style.height = '100%';
    camera.aspect = w / Math.max(h, 1);
    camera.updateProjectionMatrix();
    sun.position.copy(camera.position);
    renderer.render(world, camera);
  }
  window.addEventListener('resize', draw);
  controls.update();
  draw();
  document.body.dataset.ready = '1';
} catch (e) {
  fail(e);
}
