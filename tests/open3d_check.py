"""Open3D reads a scan folder right (tests/open3d_check.sh runs it on a 4-view bunny scan).

- cloud.ply and frames/view_001.ply load with normals; the frame's normals face the camera of its
  `comment camera_pose x y z qw qx qy qz` (dot(n, camera - p) > 0 for more than 95 % of points);
- cloud.ply lies on the true mesh (object.stl): median point-to-surface distance under 1 mm
  (the twin's depth is exact; the 2 mm voxel grid moves a point by at most 1.7 mm);
- mesh.ply loads as a triangle mesh; points sampled on it lie on the true mesh (median under 1 mm);
- depth/view_001.png is 16-bit in 0.1 mm (depth_scale 10000); view_001.json read by Open3D's own
  read_pinhole_camera_intrinsic gives the camera's matrix (not the identity); back-projected by
  Open3D with those intrinsics, depth_scale and pose it lands on the frame's points (median nearest
  distance under 2 mm);
- trajectory.json read by read_pinhole_camera_trajectory holds one camera per depth image, each
  extrinsic the inverse of its view's pose;
- mesh.obj loads with vertex normals that agree with mesh.ply's;
- scan.json, coverage.json and every PLY header name the pbnbv version that wrote them.
"""
import json
import sys

import numpy as np
import open3d as o3d

scan = sys.argv[1]
failures = []


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        failures.append(what)


def camera_pose(path):
    with open(path, "rb") as f:
        for line in f:
            line = line.decode("ascii", "replace").strip()
            if line.startswith("comment camera_pose "):
                return [float(v) for v in line.split()[2:]]
            if line == "end_header":
                break
    return None


def distances_to(points, mesh):
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(o3d.t.geometry.TriangleMesh.from_legacy(mesh))
    return scene.compute_distance(o3d.core.Tensor(np.asarray(points), dtype=o3d.core.Dtype.Float32)).numpy()


truth = o3d.io.read_triangle_mesh(f"{scan}/object.stl")
check(len(truth.triangles) > 0, f"object.stl loads ({len(truth.triangles)} triangles)")

cloud = o3d.io.read_point_cloud(f"{scan}/cloud.ply")
check(len(cloud.points) > 1000 and cloud.has_normals(), f"cloud.ply loads with normals ({len(cloud.points)} points)")
d = distances_to(cloud.points, truth)
check(np.median(d) < 0.001, f"cloud.ply median distance to the true mesh {np.median(d) * 1e3:.3f} mm (< 1 mm)")

frame = o3d.io.read_point_cloud(f"{scan}/frames/view_001.ply")
pose = camera_pose(f"{scan}/frames/view_001.ply")
check(pose is not None and len(pose) == 7, f"frames/view_001.ply names its camera pose ({pose})")
p = np.asarray(frame.points)
n = np.asarray(frame.normals)
facing = np.mean(np.sum(n * (np.asarray(pose[:3]) - p), axis=1) > 0)
check(frame.has_normals() and facing > 0.95, f"frame normals face the camera for {facing * 100:.1f} % of points (> 95 %)")

mesh = o3d.io.read_triangle_mesh(f"{scan}/mesh.ply")
check(len(mesh.triangles) > 1000, f"mesh.ply loads ({len(mesh.triangles)} triangles, {len(mesh.vertices)} vertices)")
samples = mesh.sample_points_uniformly(50000)
d = distances_to(samples.points, truth)
check(np.median(d) < 0.001, f"mesh.ply median distance to the true mesh {np.median(d) * 1e3:.3f} mm (< 1 mm)")

depth = o3d.io.read_image(f"{scan}/depth/view_001.png")
arr = np.asarray(depth)
check(arr.dtype == np.uint16 and arr.max() > 0, f"depth/view_001.png is 16-bit ({arr.dtype}, max {arr.max()} units)")
meta = json.load(open(f"{scan}/depth/view_001.json"))
check(meta["depth_scale"] == 10000, f"depth/view_001.json: depth_scale {meta['depth_scale']} (0.1 mm: 10000)")
K = o3d.io.read_pinhole_camera_intrinsic(f"{scan}/depth/view_001.json")
want = np.array([[meta["fx"], 0, meta["cx"]], [0, meta["fy"], meta["cy"]], [0, 0, 1]])
check(K.width == meta["width"] and K.height == meta["height"] and np.allclose(K.intrinsic_matrix, want),
      f"Open3D's read_pinhole_camera_intrinsic reads view_001.json: {K.width} x {K.height}, "
      f"fx {K.intrinsic_matrix[0, 0]}, cx {K.intrinsic_matrix[0, 2]}")
pos = np.asarray(meta["object_T_camera"]["position_m"])
w, x, y, z = meta["object_T_camera"]["quat_wxyz"]
T = np.eye(4)
T[:3, :3] = o3d.geometry.get_rotation_matrix_from_quaternion([w, x, y, z])
T[:3, 3] = pos
back = o3d.geometry.PointCloud.create_from_depth_image(depth, K, np.linalg.inv(T), depth_scale=meta["depth_scale"],
                                                       depth_trunc=meta.get("depth_max_m", 10.0))
near = np.asarray(back.compute_point_cloud_distance(frame))
check(len(back.points) > 1000 and np.median(near) < 0.002,
      f"the depth image back-projected with its intrinsics and pose: {len(back.points)} points, "
      f"median {np.median(near) * 1e3:.3f} mm from the frame's (< 2 mm)")

import glob
views = sorted(glob.glob(f"{scan}/depth/view_*.json"))
traj = o3d.io.read_pinhole_camera_trajectory(f"{scan}/trajectory.json")
check(len(traj.parameters) == len(views) and len(views) > 0,
      f"trajectory.json: {len(traj.parameters)} cameras for {len(views)} depth images")
worst = 0.0
for p_, v in zip(traj.parameters, views):
    m = json.load(open(v))
    w_, x_, y_, z_ = m["object_T_camera"]["quat_wxyz"]
    Tv = np.eye(4)
    Tv[:3, :3] = o3d.geometry.get_rotation_matrix_from_quaternion([w_, x_, y_, z_])
    Tv[:3, 3] = m["object_T_camera"]["position_m"]
    worst = max(worst, np.abs(np.asarray(p_.extrinsic) @ Tv - np.eye(4)).max())
check(worst < 1e-9, f"each trajectory extrinsic is the inverse of its view's pose (worst {worst:.2e})")

obj = o3d.io.read_triangle_mesh(f"{scan}/mesh.obj")
mesh.compute_triangle_normals()
agree = 0.0
if obj.has_vertex_normals() and len(obj.vertex_normals) == len(mesh.vertex_normals):
    agree = np.median(np.sum(np.asarray(obj.vertex_normals) * np.asarray(mesh.vertex_normals), axis=1))
check(obj.has_vertex_normals() and agree > 0.999,
      f"mesh.obj loads with vertex normals ({len(obj.vertex_normals)}), median agreement with mesh.ply's {agree:.4f}")

version = json.load(open(f"{scan}/scan.json")).get("pbnbv_version")
check(bool(version), f"scan.json names pbnbv {version}")
if glob.glob(f"{scan}/coverage.json"):
    check(json.load(open(f"{scan}/coverage.json")).get("pbnbv_version") == version, "coverage.json names the same version")
for ply in ["cloud.ply", "mesh.ply", "frames/view_001.ply"]:
    with open(f"{scan}/{ply}", "rb") as f:
        head = f.read(400).decode("ascii", "replace")
    check(f"comment written by pbnbv {version}" in head, f"{ply}'s header names pbnbv {version}")

sys.exit(1 if failures else 0)
