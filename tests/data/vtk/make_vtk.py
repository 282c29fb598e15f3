# Writes the VTK test meshes from cube_gmsh.vtk (Gmsh's legacy ASCII export of
# ../msh/cube_v41.msh: points, lines, triangles and tets). Regenerate with
#   gmsh ../msh/cube_v41.msh -save -o cube_gmsh.vtk
#   /usr/bin/python3 make_vtk.py        (Debian's python3-vtk9)
# cube_appended.vtu: XML, appended raw data, zlib-compressed; cube_ascii.vtu: XML, ASCII;
# cube_binary.vtk: legacy binary. All keep Gmsh's mixed cells, so readers must skip non-tets.
import vtk

reader = vtk.vtkUnstructuredGridReader()
reader.SetFileName("cube_gmsh.vtk")
reader.Update()
grid = reader.GetOutput()

writer = vtk.vtkXMLUnstructuredGridWriter()
writer.SetInputData(grid)
writer.SetFileName("cube_appended.vtu")
writer.SetDataModeToAppended()
writer.SetCompressorTypeToZLib()
writer.Write()

writer.SetFileName("cube_ascii.vtu")
writer.SetDataModeToAscii()
writer.SetCompressorTypeToNone()
writer.Write()

legacy = vtk.vtkUnstructuredGridWriter()
legacy.SetInputData(grid)
legacy.SetFileName("cube_binary.vtk")
legacy.SetFileTypeToBinary()
legacy.Write()
