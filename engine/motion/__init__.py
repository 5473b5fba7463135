"""Motion I/O: BVH reading and writing, rig profiles, retargeting to and from the canonical
skeleton, and the :class:`~engine.motion.clip.Motion` clip type."""
