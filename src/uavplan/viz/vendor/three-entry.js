// The part of three.js the viewer uses, bundled into one minified script that defines the
// global THREE (see BUILD.md). A class the viewer starts to use is added here and the bundle
// rebuilt; the browser test fails on a missing one.
export {
  BufferAttribute, BufferGeometry, CircleGeometry, Color, ColorManagement, CylinderGeometry,
  DoubleSide, DynamicDrawUsage, ExtrudeGeometry, Float32BufferAttribute, InstancedMesh, Line,
  LineBasicMaterial, LineDashedMaterial, LineSegments, LinearSRGBColorSpace, Matrix4, Mesh,
  MeshBasicMaterial, PerspectiveCamera, Points, Scene, ShaderMaterial, Shape, SphereGeometry,
  Vector2, Vector3, WebGLRenderTarget, WebGLRenderer,
} from "three";
export { OrbitControls } from "three/addons/controls/OrbitControls.js";
