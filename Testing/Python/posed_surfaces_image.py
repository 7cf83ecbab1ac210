"""Image baselines: the demo's render.png on the tiny phantom, and the posed surfaces of the tiny
fixture rendered from the side."""
import os
import sys

from vtkmodules.vtkIOXML import vtkXMLPolyDataReader
from vtkmodules.vtkRenderingCore import (vtkActor, vtkPolyDataMapper, vtkRenderer, vtkRenderWindow,
                                         vtkWindowToImageFilter)
from vtkmodules.vtkIOImage import vtkPNGWriter
import vtkmodules.vtkRenderingOpenGL2  # noqa: F401
import vtkmodules.vtkInteractionStyle  # noqa: F401

from repose_testing import TEMP, TINY, compare_with_baseline, run

failures = []
demo = os.path.join(TEMP, "demo_tiny")
run("demo", "--size", "tiny", "--out", demo)
if not compare_with_baseline(os.path.join(demo, "render.png"), "DemoRenderTiny"):
    failures.append("DemoRenderTiny")

reader = vtkXMLPolyDataReader()
reader.SetFileName(f"{TINY}/posed_dqs/posed_surfaces.vtp")
reader.Update()
mapper = vtkPolyDataMapper()
mapper.SetInputConnection(reader.GetOutputPort())
mapper.SetScalarModeToUseCellFieldData()
mapper.SelectColorArray("Label")
mapper.SetScalarRange(0, 35)
actor = vtkActor()
actor.SetMapper(mapper)
ren = vtkRenderer()
ren.AddActor(actor)
ren.SetBackground(1, 1, 1)
cam = ren.GetActiveCamera()
cam.SetPosition(-1, 0, 0)  # from the patient's right (LPS: right is -x)
cam.SetFocalPoint(0, 0, 0)
cam.SetViewUp(0, 0, 1)
ren.ResetCamera()
win = vtkRenderWindow()
win.SetOffScreenRendering(1)
win.SetSize(400, 600)
win.AddRenderer(ren)
win.Render()
grab = vtkWindowToImageFilter()
grab.SetInput(win)
grab.Update()
png = os.path.join(TEMP, "PosedSurfacesTiny.png")
w = vtkPNGWriter()
w.SetFileName(png)
w.SetInputConnection(grab.GetOutputPort())
w.Write()
if not compare_with_baseline(png, "PosedSurfacesTiny"):
    failures.append("PosedSurfacesTiny")
print(f"{2 - len(failures)} passed, {len(failures)} failed")
sys.exit(1 if failures else 0)
