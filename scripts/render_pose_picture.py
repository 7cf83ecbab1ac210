"""Renders a case's rest surfaces beside a pose's (skin translucent, bones opaque) seen from the
patient's left, as the README's picture: scripts/render_pose_picture.py CASE_DIR POSED_DIR OUT.png
"TITLE". Run under xvfb-run with Debian's python3 and the build's Python package on PYTHONPATH.
The README's picture: the Visible Human female of Testing/Python/visible_human_pose.py."""
import sys

import vtkmodules.vtkInteractionStyle  # noqa: F401 - rendering back ends
import vtkmodules.vtkRenderingFreeType  # noqa: F401
import vtkmodules.vtkRenderingOpenGL2  # noqa: F401
from vtkmodules.vtkFiltersCore import vtkThreshold
from vtkmodules.vtkFiltersGeometry import vtkGeometryFilter
from vtkmodules.vtkIOImage import vtkPNGWriter
from vtkmodules.vtkIOXML import vtkXMLPolyDataReader
from vtkmodules.vtkRenderingCore import (vtkActor, vtkPolyDataMapper, vtkRenderer, vtkRenderWindow, vtkTextActor,
                                         vtkWindowToImageFilter)

BONE, SKIN = (0.93, 0.87, 0.70), (0.85, 0.6, 0.5)


def part(path, lo, hi, colour, opacity):
    """The surfaces' cells whose Label lies in [lo, hi] (the skin is -1, bones their label values)."""
    reader = vtkXMLPolyDataReader()
    reader.SetFileName(path)
    threshold = vtkThreshold()
    threshold.SetInputConnection(reader.GetOutputPort())
    threshold.SetInputArrayToProcess(0, 0, 0, 1, "Label")
    threshold.SetLowerThreshold(lo)
    threshold.SetUpperThreshold(hi)
    threshold.SetThresholdFunction(vtkThreshold.THRESHOLD_BETWEEN)
    geometry = vtkGeometryFilter()
    geometry.SetInputConnection(threshold.GetOutputPort())
    mapper = vtkPolyDataMapper()
    mapper.SetInputConnection(geometry.GetOutputPort())
    mapper.ScalarVisibilityOff()
    actor = vtkActor()
    actor.SetMapper(mapper)
    actor.GetProperty().SetColor(*colour)
    actor.GetProperty().SetOpacity(opacity)
    return actor


def main(case_dir, posed_dir, out, title):
    window = vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.SetSize(1200, 900)
    window.SetMultiSamples(8)
    renderers = []
    for i, (path, caption) in enumerate(((f"{case_dir}/surfaces.vtp", "rest (as scanned)"),
                                         (f"{posed_dir}/posed_surfaces.vtp", title))):
        renderer = vtkRenderer()
        renderer.SetViewport(0.5 * i, 0, 0.5 * (i + 1), 1)
        renderer.SetBackground(1, 1, 1)
        renderer.AddActor(part(path, 0, 1e9, BONE, 1.0))
        renderer.AddActor(part(path, -1, -1, SKIN, 0.22))
        text = vtkTextActor()
        text.SetInput(caption)
        text.GetTextProperty().SetFontSize(24)
        text.GetTextProperty().SetColor(0.1, 0.1, 0.1)
        text.SetPosition(20, 20)
        renderer.AddActor2D(text)
        window.AddRenderer(renderer)
        renderers.append(renderer)
    # One camera for both, from the patient's left and a little in front (LPS: +x left, -y anterior).
    camera = renderers[0].GetActiveCamera()
    camera.SetViewUp(0, 0, 1)
    camera.SetPosition(1.0, -0.45, 0.12)
    camera.SetFocalPoint(0, 0, 0)
    renderers[1].SetActiveCamera(camera)
    renderers[0].ResetCamera()
    camera.Zoom(1.3)
    window.Render()
    grab = vtkWindowToImageFilter()
    grab.SetInput(window)
    writer = vtkPNGWriter()
    writer.SetFileName(out)
    writer.SetInputConnection(grab.GetOutputPort())
    writer.Write()


if __name__ == "__main__":
    if len(sys.argv) != 5:
        sys.exit(__doc__)
    main(*sys.argv[1:])
