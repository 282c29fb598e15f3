// Box [0,2]x[0,1]x[0,0.5] (volume 1) for the MSH reader tests. Regenerate with
//   gmsh -3 cube.geo -format msh41 -o cube_v41.msh
//   gmsh cube_v41.msh -save -format msh22 -o cube_v22.msh
//   gmsh cube_v41.msh -save -format msh41 -bin -o cube_v41_bin.msh
//   gmsh cube_v41.msh -save -format msh22 -bin -o cube_v22_bin.msh
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 2, 1, 0.5};
Mesh.MeshSizeMax = 0.4;
Mesh.MeshSizeMin = 0.4;
