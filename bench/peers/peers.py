# Peer renderers for bench/peers/run_peers.sh, run with pvbatch (ParaView 5.11) under xvfb-run:
#   pvbatch peers.py paraview|vtk|both NETCDF SIZE FRAMES RESAMPLE_N VARIABLE
# Both read the contest netCDF file with ParaView's NetCDF reader (vtkNetCDFCFReader) in spherical
# coordinates, dimensions "(lat, r, lon)", resample it to an N^3 Cartesian image (Resample To Image)
# and volume-render the variable with the same view (camera orbit azimuth 30, elevation 20, 19000 km,
# vertical field of view 42) and transfer function (blue-white-red over [-400, 400], opacity V 0.6 at
# the ends, transparent in [0.4, 0.6], opacity per 100 km) as bench/render_bench.cpp.
#   paraview: paraview.simple, volume representation (the default "Smart" mapper, i.e. what a user gets)
#   vtk:      vtkFixedPointVolumeRayCastMapper on the resampled image, sample distance half a voxel
#             (the ray caster's rule: half a cell), no automatic sample-distance adjustment
# Prints one line per measurement: "RESULT <peer> <what> <seconds>".
import math
import sys
import time

mode, path, size, frames, n, variable = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), int(sys.argv[5]), sys.argv[6]
az, el, dist, fov = 30.0, 20.0, 19000.0, 42.0


def camera_position(azimuth):
    a, e = math.radians(azimuth), math.radians(el)
    return [dist * math.cos(e) * math.cos(a), dist * math.cos(e) * math.sin(a), dist * math.sin(e)]


def result(what, seconds, peer=None):
    print(f"RESULT {peer or mode} {what} {seconds:.4f}", flush=True)


from paraview.simple import *  # noqa: E402

t = time.perf_counter()
reader = NetCDFReader(FileName=[path])
reader.Dimensions = '(lat, r, lon)'
reader.SphericalCoordinates = 1
reader.UpdatePipeline()
result("read", time.perf_counter() - t)

t = time.perf_counter()
resample = ResampleToImage(Input=reader)
resample.SamplingDimensions = [n, n, n]
resample.UpdatePipeline()
result(f"resample_{n}^3", time.perf_counter() - t)

if mode in ("paraview", "both"):
    view = CreateRenderView()
    view.ViewSize = [size, size]
    view.OrientationAxesVisibility = 0
    display = Show(resample, view)
    display.Representation = 'Volume'
    ColorBy(display, ('POINTS', variable))
    lut = GetColorTransferFunction(variable)
    lut.ApplyPreset('Blue - Green - Orange', True)
    lut.RGBPoints = [-400, 0.0, 0.0, 1.0, 0, 1.0, 1.0, 1.0, 400, 1.0, 0.0, 0.0]
    pwf = GetOpacityTransferFunction(variable)
    pwf.Points = [-400, 0.6, 0.5, 0.0, -80, 0.0, 0.5, 0.0, 80, 0.0, 0.5, 0.0, 400, 0.6, 0.5, 0.0]
    display.ScalarOpacityUnitDistance = 100.0
    view.CameraPosition = camera_position(az)
    view.CameraFocalPoint = [0, 0, 0]
    view.CameraViewUp = [0, 0, 1]
    view.CameraViewAngle = fov
    t = time.perf_counter()
    Render(view)
    result("first_frame", time.perf_counter() - t, "paraview")
    t = time.perf_counter()
    for i in range(frames):
        view.CameraPosition = camera_position(az + 0.5 * (i + 1))  # a new view each frame, no cached image
        Render(view)
    result("frame", (time.perf_counter() - t) / frames, "paraview")
    SaveScreenshot(f"/tmp/raypc-peers/paraview_{size}.png", view, ImageResolution=[size, size])
if mode in ("vtk", "both"):
    import os
    from vtkmodules.vtkCommonDataModel import vtkPiecewiseFunction
    from vtkmodules.vtkRenderingCore import vtkColorTransferFunction, vtkRenderer, vtkRenderWindow, vtkVolume, vtkVolumeProperty
    from vtkmodules.vtkRenderingVolume import vtkFixedPointVolumeRayCastMapper
    import vtkmodules.vtkRenderingOpenGL2  # noqa: F401  (render window implementation)
    from paraview import servermanager
    image = servermanager.Fetch(resample)
    image.GetPointData().SetActiveScalars(variable)
    spacing = image.GetSpacing()
    mapper = vtkFixedPointVolumeRayCastMapper()
    mapper.SetInputData(image)
    mapper.AutoAdjustSampleDistancesOff()
    mapper.LockSampleDistanceToInputSpacingOff()
    mapper.SetSampleDistance(0.5 * min(spacing))
    mapper.SetNumberOfThreads(os.cpu_count())
    colour = vtkColorTransferFunction()
    colour.AddRGBPoint(-400, 0, 0, 1)
    colour.AddRGBPoint(0, 1, 1, 1)
    colour.AddRGBPoint(400, 1, 0, 0)
    opacity = vtkPiecewiseFunction()
    for x, y in [(-400, 0.6), (-80, 0.0), (80, 0.0), (400, 0.6)]:
        opacity.AddPoint(x, y)
    prop = vtkVolumeProperty()
    prop.SetColor(colour)
    prop.SetScalarOpacity(opacity)
    prop.SetScalarOpacityUnitDistance(100.0)
    prop.SetInterpolationTypeToLinear()
    volume = vtkVolume()
    volume.SetMapper(mapper)
    volume.SetProperty(prop)
    renderer = vtkRenderer()
    renderer.AddVolume(volume)
    window = vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.SetSize(size, size)
    window.AddRenderer(renderer)
    cam = renderer.GetActiveCamera()
    cam.SetFocalPoint(0, 0, 0)
    cam.SetViewUp(0, 0, 1)
    cam.SetViewAngle(fov)
    cam.SetPosition(*camera_position(az))
    renderer.ResetCameraClippingRange()
    print(f"vtk: image {image.GetDimensions()} spacing {spacing[0]:.1f} km, sample distance {0.5 * min(spacing):.1f} km, "
          f"threads {mapper.GetNumberOfThreads()}", flush=True)
    t = time.perf_counter()
    window.Render()
    result("first_frame", time.perf_counter() - t, "vtk")
    t = time.perf_counter()
    for i in range(frames):
        cam.SetPosition(*camera_position(az + 0.5 * (i + 1)))
        renderer.ResetCameraClippingRange()
        window.Render()
    result("frame", (time.perf_counter() - t) / frames, "vtk")
