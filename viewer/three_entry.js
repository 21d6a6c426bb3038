// The parts of three.js the viewer page uses (viewer.js reads them from window.LAMBERT_THREE).
// build_three.sh bundles this file with the pinned three.js into three.bundle.js.
export {
  BufferAttribute, Color, DataTexture, LinearFilter, LinearSRGBColorSpace, Mesh, PerspectiveCamera,
  RGBAFormat, Scene, ShaderMaterial, DoubleSide, Vector3, WebGLRenderer, UnsignedByteType,
  LineBasicMaterial, ClampToEdgeWrapping,
} from 'three';
export { OrbitControls } from 'three/addons/controls/OrbitControls.js';
export { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
