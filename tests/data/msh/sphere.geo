// Unit ball (radius 1, centre 0) for the MSH reader tests. Regenerate with
//   gmsh -3 sphere.geo -format msh41 -o sphere_v41.msh
//   gmsh sphere_v41.msh -save -format msh22 -o sphere_v22.msh
SetFactory("OpenCASCADE");
Sphere(1) = {0, 0, 0, 1};
Mesh.MeshSizeMax = 0.35;
Mesh.MeshSizeMin = 0.35;
