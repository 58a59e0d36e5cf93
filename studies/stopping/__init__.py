"""When a run is done: the stop rules measured on bbob (coco-experiment)."""
