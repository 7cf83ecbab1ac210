"""The tasks of a batch: one prepare per subject, then one per pose and per clip frame. Each task has
a key, the hash of everything its result depends on (input files' contents, settings, the Repose
version), so a rerun knows what is already complete and what changed."""
import hashlib
import json
import os


def file_hash(path, _cache={}):
    """sha256 of a file's contents (cached by path, size and mtime for one run)."""
    st = os.stat(path)
    stamp = (path, st.st_size, st.st_mtime_ns)
    if stamp not in _cache:
        h = hashlib.sha256()
        with open(path, "rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                h.update(block)
        _cache[stamp] = h.hexdigest()
    return _cache[stamp]


def text_hash(text):
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def key_of(what):
    """The key of a task: sha256 of its canonical JSON description."""
    return hashlib.sha256(json.dumps(what, sort_keys=True).encode("utf-8")).hexdigest()


def folder_hash(path):
    """sha256 over a folder's files (a DICOM series): each file's name and contents, in name order."""
    h = hashlib.sha256()
    for name in sorted(os.listdir(path)):
        if os.path.isfile(os.path.join(path, name)):
            h.update(f"{name}\0{file_hash(os.path.join(path, name))}\0".encode("utf-8"))
    return h.hexdigest()


def _input(path):
    if path is None:
        return None
    if os.path.isdir(path):
        files = [os.path.join(path, n) for n in os.listdir(path) if os.path.isfile(os.path.join(path, n))]
        return {"path": path, "sha256": folder_hash(path), "bytes": sum(os.path.getsize(f) for f in files)}
    return {"path": path, "sha256": file_hash(path), "bytes": os.path.getsize(path)}


def _posing(settings, image):
    """What a posed result depends on besides its case and pose."""
    outputs = [o for o in settings["outputs"] if o != "image" or image]
    return {"skinning": settings["skinning"], "relax": settings["relax"], "outputs": outputs,
            "format": settings["format"], "image_sha256": image["sha256"] if image and "image" in outputs else None}


def plan_batch(manifest, out_dir, version, executable):
    """Subjects (inputs with hashes, case key) and tasks (prepare, pose, frame), in submission order."""
    subjects, tasks = [], []
    for s in manifest["subjects"]:
        inputs = {"labels": _input(s["labels"]), "image": _input(s["image"]),
                  "skeleton": "auto" if s["skeleton"] == "auto" else _input(s["skeleton"]),
                  "label_table": _input(s["label_table"])}
        settings = s["settings"]
        case_key = key_of({"version": version, "prepare": settings["prepare"],
                           **{k: v if isinstance(v, str) or v is None else v["sha256"] for k, v in inputs.items()}})
        subject_dir = os.path.join(out_dir, s["name"])
        case_dir = os.path.join(subject_dir, "case")
        subjects.append({"name": s["name"], "inputs": inputs, "settings": settings, "case": case_dir,
                         "case_key": case_key})
        tasks.append({"kind": "prepare", "subject": s["name"], "task": "prepare", "key": case_key,
                      "out": case_dir, "executable": executable, "labels": s["labels"], "image": s["image"],
                      "skeleton": s["skeleton"], "label_table": s["label_table"], "prepare": settings["prepare"]})
        posing = _posing(settings, inputs["image"])
        common = {"subject": s["name"], "case": case_dir, "case_key": case_key, "image": s["image"], **posing}
        for p in s["poses"]:
            text = p.get("text")
            pose_hash = file_hash(p["file"]) if text is None else text_hash(text)
            tasks.append({**common, "kind": "pose", "task": p["name"], "pose_file": p.get("file"), "pose_text": text,
                          "pose": {"path": p.get("file"), "sha256": pose_hash},
                          "out": os.path.join(subject_dir, "poses", p["name"]),
                          "key": key_of({"case": case_key, "pose": pose_hash, **posing})})
        for clip in s["clips"]:
            retarget = {k: clip[k] for k in ("mode", "reference_frame", "root_motion", "unit_mm")}
            clip_inputs = {"bvh": _input(clip["file"]), "map": _input(clip["map"])}
            for f in clip["frames"]:
                what = {"case": case_key, "bvh": clip_inputs["bvh"]["sha256"], "frame": f, **retarget,
                        "map": clip_inputs["map"] and clip_inputs["map"]["sha256"], **posing}
                tasks.append({**common, "kind": "frame", "task": f"{clip['name']}/frame_{f:05d}", "frame": f,
                              "bvh": clip["file"], "map": clip["map"], "retarget": retarget, "clip": clip_inputs,
                              "out": os.path.join(subject_dir, "clips", clip["name"], f"frame_{f:05d}"),
                              "key": key_of(what)})
    return subjects, tasks
