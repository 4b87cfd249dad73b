"""Pictures of a solved mechanism: one scene (:mod:`.scene`), drawn by matplotlib (:mod:`.draw`, :mod:`.animate`).

matplotlib is imported only by the drawing modules, never by ``import linkagekit``.
"""
