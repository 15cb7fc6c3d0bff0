"""What a scene needs (docs/need.md), in two modules callers import by name:

- :mod:`.analysis`: what some frames' request streams touch in a texture set (textures, levels,
  level groups, blocks, codewords, memory words, block-buffer and cache hits): ``analyse``,
  ``NeedCounter``, ``scene_streams``;
- :mod:`.prune`: a texture set of only that (absent levels, block presence bits, narrower indices),
  and encoding for some frames only (``prune``, ``encode_needed``).

Nothing is re-exported here: ``from vqtex.golden.need.analysis import analyse``.
"""
