# What a ParaView user does to see ASPECT's output as a volume, for bench/aspect_resample/run.sh.
# Run with pvbatch (ParaView 5.11) under xvfb-run:
#   pvbatch pv_first_picture.py SOLUTION_PVD OUT_PNG SIZE RESAMPLE_N
# Opens the collection (PVDReader: .pvd -> .pvtu -> .vtu pieces) at its first time, resamples it
# onto an N^3 Cartesian image over the mesh's bounds (Resample To Image), shows the image as a Volume
# representation coloured by T (ParaView's default "Smart" mapper and colour map, the camera reset
# to the data) and saves one SIZE x SIZE frame. Prints one line of JSON with the seconds of each
# phase (time.perf_counter, after ParaView's import):
#   read      PVDReader.UpdatePipeline: parse and decompress every piece of the first step
#   resample  ResampleToImage.UpdatePipeline: probe the unstructured mesh at N^3 points
#   frame     Show + Volume representation + Render + SaveScreenshot
#   total     the three added up
# and the mesh's cells and points, T's range, and VTK's thread back-end (vtkSMPTools) and threads.
import json
import sys
import time

pvd, png, size, n = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])

from paraview.simple import (  # noqa: E402  (the import is not timed: it is ParaView's start-up)
    ColorBy, CreateRenderView, PVDReader, Render, ResampleToImage, SaveScreenshot, Show)
from vtkmodules.vtkCommonCore import vtkSMPTools  # noqa: E402

t0 = time.perf_counter()
reader = PVDReader(FileName=pvd)
steps = reader.TimestepValues  # a list, or one number for a single step
first_time = float(min(steps) if hasattr(steps, "__len__") else steps)
reader.UpdatePipeline(first_time)
t1 = time.perf_counter()

resample = ResampleToImage(Input=reader)
resample.SamplingDimensions = [n, n, n]
resample.UpdatePipeline(first_time)
t2 = time.perf_counter()

view = CreateRenderView()
view.ViewSize = [size, size]
view.OrientationAxesVisibility = 0
view.ViewTime = first_time
display = Show(resample, view)
display.Representation = "Volume"
ColorBy(display, ("POINTS", "T"))
display.RescaleTransferFunctionToDataRange(True, False)
view.ResetCamera()
Render(view)
SaveScreenshot(png, view, ImageResolution=[size, size])
t3 = time.perf_counter()

info = reader.GetDataInformation()
smp = vtkSMPTools()
print(json.dumps({
    "read": round(t1 - t0, 4), "resample": round(t2 - t1, 4), "frame": round(t3 - t2, 4), "total": round(t3 - t0, 4),
    "cells": info.GetNumberOfCells(), "points": info.GetNumberOfPoints(), "time": first_time,
    "T_range": list(reader.PointData["T"].GetRange()), "resample_n": n, "size": size,
    "smp_backend": smp.GetBackend(), "smp_threads": smp.GetEstimatedNumberOfThreads()}), flush=True)
