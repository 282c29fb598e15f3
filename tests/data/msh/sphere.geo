// Unit ball (radius 1, centre 0) for the MSH reader tests. Regenerate with
//   gmsh -3 sphere.geo -format msh41 -o sphere_v41.msh
//   gmsh sphere_v41.msh -save -format msh22 -o sphere_v22.msh
//   gmsh sphere_v41.msh -save -format msh41 -bin -o sphere_v41_bin.msh
//   gmsh sphere_v41.msh -save -format msh22 -bin -o sphere_v22_bin.msh
SetFactory("OpenCASCADE");
Sphere(1) = {0, 0, 0, 1};
Mesh.MeshSizeMax = 0.35;
Mesh.MeshSizeMin = 0.35;
