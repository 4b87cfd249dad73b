"""The self-contained report page (:mod:`.report`) and its one small SVG viewer (``viewer.js``)."""
