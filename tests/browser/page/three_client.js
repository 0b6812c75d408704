// Loads the pack with three.js's GLTFLoader, which has no MSFT_lod support and so shows the scene's
// node, LOD0; renders it with and without its base colour textures and posts the measurements.
import * as THREE from "three";
import { GLTFLoader } from "three/addons/loaders/GLTFLoader.js";
import { MeshoptDecoder } from "three/addons/libs/meshopt_decoder.module.js";

const probe = window.lodbakeProbe;
try {
    const canvas = probe.makeCanvas();
    const renderer = new THREE.WebGLRenderer({ canvas, preserveDrawingBuffer: true, antialias: false });
    renderer.setPixelRatio(1);
    renderer.setSize(probe.params.width, probe.params.height, false);
    renderer.setClearColor(new THREE.Color(0.05, 0.1, 0.2), 1);
    const scene = new THREE.Scene();
    const camera = new THREE.PerspectiveCamera(45, probe.params.width / probe.params.height, 0.01, 1000);
    renderer.render(scene, camera);
    const background = probe.backgroundOf(probe.readPixels(canvas));

    const gltf = await new GLTFLoader().setMeshoptDecoder(MeshoptDecoder).loadAsync(probe.params.pack);
    scene.add(gltf.scene);
    const box = new THREE.Box3().setFromObject(gltf.scene);
    const sphere = box.getBoundingSphere(new THREE.Sphere());
    if (!(sphere.radius > 0)) sphere.radius = 1; // nothing to frame: the render shows it as blank
    const distance = sphere.radius / Math.sin(THREE.MathUtils.degToRad(camera.fov / 2));
    camera.position.copy(sphere.center).add(new THREE.Vector3(0, 0, distance));
    camera.near = distance / 100;
    camera.far = distance * 3;
    camera.lookAt(sphere.center);
    camera.updateProjectionMatrix();
    scene.add(new THREE.AmbientLight(0xffffff, 0.8));
    const light = new THREE.DirectionalLight(0xffffff, 2);
    light.position.copy(camera.position);
    scene.add(light);

    const meshes = [];
    gltf.scene.traverse((o) => { if (o.isMesh) meshes.push(o); });
    const render = () => { renderer.render(scene, camera); return probe.readPixels(canvas); };
    const textured = render();
    const textures = meshes.filter((m) => m.material.map && m.material.map.image)
        .map((m) => ({ mesh: m.name, width: m.material.map.image.width, height: m.material.map.image.height }));
    const result = {
        client: "three", version: THREE.REVISION,
        canvas: { width: canvas.width, height: canvas.height },
        render: { width: renderer.domElement.width, height: renderer.domElement.height },
        drawnMeshes: meshes.map((m) => ({
            name: m.name,
            indices: m.geometry.index ? m.geometry.index.count : m.geometry.attributes.position.count,
        })),
        textures, background,
        textured: probe.measure(textured, background), png: textured.png,
    };
    if (textures.length) {
        for (const m of meshes) { m.material.map = null; m.material.needsUpdate = true; }
        const flat = render();
        result.untextured = probe.measure(flat, background);
        result.texturedVsUntextured = probe.difference(textured, flat, background);
        result.albedo = probe.albedoVariation(textured, flat, background);
    }
    probe.post(result);
} catch (error) {
    probe.fail(error);
}
