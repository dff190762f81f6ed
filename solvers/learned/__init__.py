"""Learned policies: the paper's pointer network (drl) and an attention model (am)."""
