"""Facade photos to regular layouts (mueller2007, with a learned facade parser)."""

#: How ``layout_from_photo`` finds elements: ``learned`` (the trained parser, :mod:`citygen_photo.learned`) or
#: ``contrast`` (the intensity contrast test and element library of :mod:`citygen_photo.photo`, mueller2007 as
#: published). Here, not in the analysis, so the command line offers them without importing it.
PARSERS = ("learned", "contrast")
