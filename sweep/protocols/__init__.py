"""The loadings a sweep applies, one folder each: the stop (the drive halts after steady sliding) and the driven scene
(the drive keeps its velocity)."""
