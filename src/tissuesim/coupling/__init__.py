"""Organs (FEM bodies) and the connective tissue (a frame-based body) that ties them, solved as
one system: attachment, retraction, dissection and tearing. See docs/coupling.md."""
