#!/usr/bin/env python3
"""Open3D's ScalableTSDFVolume as a peer in bench/run.sh: the same TUM-layout frames, the same
poses (a TUM trajectory, e.g. the keyframe file rgbdmap writes when every frame is a keyframe),
the same intrinsics and depth range; prints one JSON object with what the table needs.

usage: open3d_tsdf.py SEQUENCE POSES OUT.pcd --every N --fx .. --fy .. --cx .. --cy ..
"""
import argparse
import bisect
import json
import resource
import sys
import time


def read_list(path):
    entries = []
    with open(path) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            fields = line.split()
            entries.append((float(fields[0]), fields[1:]))
    return entries


def nearest(stamps, t):
    i = bisect.bisect_left(stamps, t)
    best = None
    for j in (i - 1, i):
        if 0 <= j < len(stamps) and (best is None or abs(stamps[j] - t) < abs(stamps[best] - t)):
            best = j
    return best


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("sequence")
    parser.add_argument("poses")
    parser.add_argument("out")
    parser.add_argument("--every", type=int, default=1)
    parser.add_argument("--voxel", type=float, default=0.01)
    parser.add_argument("--trunc", type=float, default=0.04)
    parser.add_argument("--max-depth", type=float, default=4.0)
    parser.add_argument("--depth-scale", type=float, default=5000.0)
    for k in ("fx", "fy", "cx", "cy"):
        parser.add_argument("--" + k, type=float, required=True)
    a = parser.parse_args()
    try:
        import numpy as np
        import open3d as o3d
    except ImportError as e:
        print("open3d_tsdf.py: %s" % e, file=sys.stderr)
        return 3

    rgb = read_list(a.sequence + "/rgb.txt")
    depth = read_list(a.sequence + "/depth.txt")
    depth_stamps = [t for t, _ in depth]
    poses = {round(t, 4): f for t, f in read_list(a.poses)}
    intrinsic = o3d.camera.PinholeCameraIntrinsic(640, 480, a.fx, a.fy, a.cx, a.cy)
    volume = o3d.pipelines.integration.ScalableTSDFVolume(
        voxel_length=a.voxel, sdf_trunc=a.trunc,
        color_type=o3d.pipelines.integration.TSDFVolumeColorType.RGB8)

    start = time.time()
    frames = fused = 0
    for i, (t, fields) in enumerate(rgb):
        frames += 1
        if i % a.every:
            continue
        pose = poses.get(round(t, 4))
        j = nearest(depth_stamps, t)
        if pose is None or j is None or abs(depth_stamps[j] - t) > 0.02:
            continue
        color = o3d.io.read_image(a.sequence + "/" + fields[0])
        d = o3d.io.read_image(a.sequence + "/" + depth[j][1][0])
        rgbd = o3d.geometry.RGBDImage.create_from_color_and_depth(
            color, d, depth_scale=a.depth_scale, depth_trunc=a.max_depth,
            convert_rgb_to_intensity=False)
        tx, ty, tz, qx, qy, qz, qw = (float(x) for x in pose)
        T = np.eye(4)
        T[:3, :3] = o3d.geometry.get_rotation_matrix_from_quaternion([qw, qx, qy, qz])
        T[:3, 3] = [tx, ty, tz]
        volume.integrate(rgbd, intrinsic, np.linalg.inv(T))
        fused += 1
    cloud = volume.extract_point_cloud()
    seconds = time.time() - start
    o3d.io.write_point_cloud(a.out, cloud, write_ascii=False)
    print(json.dumps({
        "frames": frames, "keyframes": fused, "wall_seconds": seconds,
        "frames_per_second": frames / seconds if seconds > 0 else 0,
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
        "map_points": len(cloud.points)}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
