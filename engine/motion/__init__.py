"""Motion I/O: BVH reading and writing, glTF 2.0 export (:mod:`engine.motion.formats` picks
the writer by extension), rig profiles, retargeting to and from the canonical skeleton,
and the :class:`~engine.motion.clip.Motion` clip type."""
