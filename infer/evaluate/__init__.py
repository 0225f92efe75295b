"""evaluate: the methods' areas against a lab's own hand-labelled frames."""
