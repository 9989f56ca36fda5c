"""Bridges to other CAD tools (cadquery / CQ-editor). Importing this package imports nothing
heavy; each bridge imports its CAD library inside its functions."""
