"""Checks of the path tracer: its speed against Mitsuba 3's, and whether two builds draw the same images."""
