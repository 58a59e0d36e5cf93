"""Studies on Mitsuba 3: every task on its Mitsuba twin, Mitsuba's own gradient, the two renderers' agreement."""
