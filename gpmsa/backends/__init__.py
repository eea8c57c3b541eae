"""Computational backends for gpmsa (numpy reference, torch, pyro)."""
