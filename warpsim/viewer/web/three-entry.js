export {
  Scene, PerspectiveCamera, WebGLRenderer, BufferGeometry, BufferAttribute, Float32BufferAttribute, Mesh,
  MeshLambertMaterial, MeshBasicMaterial, LineBasicMaterial, Line, CylinderGeometry, SphereGeometry,
  HemisphereLight, DirectionalLight, AmbientLight, Color, Fog, Vector3, Quaternion, Matrix4, DoubleSide, InstancedMesh,
  DynamicDrawUsage,
} from 'three';
