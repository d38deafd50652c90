"""Render a city stage with Blender's USD importer and Cycles on the CPU, for a look at what a DCC tool gets.

    pip install bpy
    python docs/render_city.py out/helsinki.usdc docs/img/helsinki.jpg [--distance 0.35] [--elevation 30]
                               [--azimuth -60] [--samples 12]
    python docs/render_city.py out/helsinki.usdc street.jpg --eye -60 -330 1.7 --target -118 -371 12 --lens 24


Run it in its own interpreter: bpy bundles its own USD, which must not meet usd-core in one process. The camera
looks at the median of the meshes' bounds from ``distance`` times the city's x extent, ``elevation`` degrees above
the ground, from ``azimuth`` degrees (counter-clockwise from +x); or from ``--eye`` towards ``--target`` (the
stage's metres, z up: a street-level look at a building); one sun, a plain sky.
"""
from __future__ import annotations

import argparse
import math
import statistics

import bpy
import mathutils


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("stage")
    parser.add_argument("out", help="image file (.jpg or .png)")
    parser.add_argument("--distance", type=float, default=0.35)
    parser.add_argument("--elevation", type=float, default=30.0)
    parser.add_argument("--azimuth", type=float, default=-60.0)
    parser.add_argument("--samples", type=int, default=12)
    parser.add_argument("--size", type=int, nargs=2, default=(1280, 720))
    parser.add_argument("--eye", type=float, nargs=3, metavar=("X", "Y", "Z"))
    parser.add_argument("--target", type=float, nargs=3, metavar=("X", "Y", "Z"))
    parser.add_argument("--lens", type=float, default=35.0, help="focal length, mm")
    args = parser.parse_args()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    assert bpy.ops.wm.usd_import(filepath=args.stage, mtl_name_collision_mode="REFERENCE_EXISTING") == {"FINISHED"}
    scene = bpy.context.scene
    corners = [o.matrix_world @ mathutils.Vector(c) for o in bpy.data.objects if o.type == "MESH" for c in o.bound_box]
    xs, ys = [c.x for c in corners], [c.y for c in corners]
    centre = mathutils.Vector((statistics.median(xs), statistics.median(ys), 10.0))
    d, el, az = args.distance * (max(xs) - min(xs)), math.radians(args.elevation), math.radians(args.azimuth)
    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    camera.data.lens, camera.data.clip_end = args.lens, 20000.0
    camera.location = centre + d * mathutils.Vector((math.cos(az) * math.cos(el), math.sin(az) * math.cos(el),
                                                     math.sin(el)))
    if args.eye and args.target:
        camera.location, centre = mathutils.Vector(args.eye), mathutils.Vector(args.target)
    camera.rotation_euler = (centre - camera.location).to_track_quat("-Z", "Y").to_euler()
    sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
    sun.data.energy, sun.rotation_euler = 3.5, (math.radians(50), 0.0, math.radians(30))
    for obj in (camera, sun):
        scene.collection.objects.link(obj)
    scene.camera = camera
    scene.world = bpy.data.worlds.new("sky")
    sky = scene.world.node_tree.nodes["Background"]  # (a world's plain colour does not light a Cycles render)
    sky.inputs["Color"].default_value, sky.inputs["Strength"].default_value = (0.6, 0.7, 0.85, 1.0), 1.0
    scene.render.engine, scene.cycles.device, scene.cycles.samples = "CYCLES", "CPU", args.samples
    scene.render.resolution_x, scene.render.resolution_y = args.size
    if args.out.lower().endswith((".jpg", ".jpeg")):
        scene.render.image_settings.file_format, scene.render.image_settings.quality = "JPEG", 85
    scene.render.filepath = args.out
    bpy.ops.render.render(write_still=True)


if __name__ == "__main__":
    main()
