// The VR controllers' real models: three's XRControllerModelFactory, which
// picks the WebXR input profile of the device, with a glTF loader that
// fetches the model from our own server and logs (and counts) a model that
// fails to load instead of throwing. This module, with the glTF loader it
// brings (≈ 30 KB compressed), is imported only when VR is entered or the
// page finds a headset (xr.js, loadModels), never with the page: a
// customer's first picture does not wait for it.

import { XRControllerModelFactory } from 'three/addons/webxr/XRControllerModelFactory.js';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';

/** A GLTFLoader that logs a controller model that fails to load (the factory's own handler would throw) and counts it. */
class ControllerModelLoader extends GLTFLoader {
  constructor() {
    super();
    /** How many models failed to load. */
    this.failures = 0;
  }

  load(url, onLoad, onProgress) {
    super.load(url, onLoad, onProgress, (e) => {
      this.failures++;
      console.warn(`vsculpt: the controller model ${url} did not load (${e && e.message ? e.message : e}); drawing the simple controller`);
    });
  }
}

/**
 * A controller model factory loading from `path` (the served input profiles).
 * @param {string} path where the profiles and models are served
 * @param {(scene: import('three').Object3D) => void} onLoaded told of each model put under a grip
 * @returns {{ factory: XRControllerModelFactory, loader: ControllerModelLoader }}
 */
export function controllerModels(path, onLoaded) {
  const loader = new ControllerModelLoader();
  const factory = new XRControllerModelFactory(loader, onLoaded);
  factory.setPath(path);
  return { factory, loader };
}
