"""Reliability of the coupled system in the standard-normal space of its random inputs."""
