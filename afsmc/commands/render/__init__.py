"""Renderers of one command's answer: verify's strategies and witnesses, requirements' verdict lines, diagrams' strategy notes, regions' plots, simulate's strategy."""
