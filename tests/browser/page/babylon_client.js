// Loads the pack with Babylon.js's glTF loader over HTTP range requests, as a streaming client
// would, records every MSFT_lod level the loader reports (coarsest first) with the indices then
// drawn, renders the finest level with and without its base colour textures and posts the
// measurements. The loader's options stay at their defaults, as a user gets them (MSFT_lod loads
// at most maxLODsToLoad = 10 levels).
(async function () {
    "use strict";
    const probe = window.lodbakeProbe;
    // EXT_meshopt_compression: Babylon fetches meshoptimizer's decoder from its CDN and uses the
    // global MeshoptDecoder; the test serves the same decoder locally (tests run offline).
    window.MeshoptDecoder = (await import("/decoder/meshopt_decoder.module.js")).MeshoptDecoder;
    const emptyScript = new Blob([""], { type: "text/javascript" });
    BABYLON.MeshoptCompression.Configuration.decoder.url = URL.createObjectURL(emptyScript);
    const canvas = probe.makeCanvas();
    const engine = new BABYLON.Engine(canvas, false, { preserveDrawingBuffer: true, antialias: false }, false);
    const scene = new BABYLON.Scene(engine);
    scene.clearColor = new BABYLON.Color4(0.05, 0.1, 0.2, 1);

    // The indices drawn at a moment: every enabled mesh with geometry.
    const drawnIndices = () => scene.meshes.filter((m) => m.isEnabled() && m.getTotalIndices() > 0)
        .reduce((sum, m) => sum + m.getTotalIndices(), 0);
    const lodEvents = [];
    let lodExtension = false;
    let complete = null;
    BABYLON.SceneLoader.OnPluginActivatedObservable.addOnce((loader) => {
        loader.onExtensionLoadedObservable.add((extension) => {
            if (extension.name !== "MSFT_lod") return;
            lodExtension = true;
            extension.onNodeLODsLoadedObservable.add((index) => lodEvents.push({ index, indices: drawnIndices() }));
        });
        complete = new Promise((resolve, reject) => {
            loader.onCompleteObservable.addOnce(resolve);
            loader.onErrorObservable.addOnce(reject);
        });
    });

    new BABYLON.FreeCamera("background", BABYLON.Vector3.Zero(), scene); // replaced once the model is in
    scene.render();
    const background = probe.backgroundOf(probe.readPixels(canvas));
    await BABYLON.AppendSceneAsync(probe.params.pack, scene,
        { pluginExtension: ".glb", pluginOptions: { gltf: { useRangeRequests: true } } });
    if (!complete) throw new Error("the glTF loader plugin was not activated");
    await complete;

    scene.createDefaultCameraOrLight(true, true, false);
    scene.activeCamera.alpha += Math.PI; // the default camera faces the model's back (glTF +z is its front)
    const render = async () => {
        await scene.whenReadyAsync();
        scene.render();
        scene.render();
        return probe.readPixels(canvas);
    };
    const textured = await render();
    const drawn = scene.meshes.filter((m) => m.isEnabled() && m.getTotalIndices() > 0);
    const textures = [];
    for (const mesh of drawn) {
        const texture = mesh.material && mesh.material.albedoTexture;
        if (texture) textures.push({ mesh: mesh.name, ...texture.getSize() });
    }
    const result = {
        client: "babylon", version: BABYLON.Engine.Version,
        canvas: { width: canvas.width, height: canvas.height },
        render: { width: engine.getRenderWidth(), height: engine.getRenderHeight() },
        msftLodExtension: lodExtension, lodEvents,
        drawnMeshes: drawn.map((m) => ({ name: m.name, indices: m.getTotalIndices() })),
        textures, background,
        textured: probe.measure(textured, background), png: textured.png,
    };
    if (textures.length) {
        for (const mesh of drawn) if (mesh.material) mesh.material.albedoTexture = null;
        const flat = await render();
        result.untextured = probe.measure(flat, background);
        result.texturedVsUntextured = probe.difference(textured, flat, background);
        result.albedo = probe.albedoVariation(textured, flat, background);
    }
    probe.post(result);
})().catch(window.lodbakeProbe.fail);
