"""The catenary and pantograph definitions, designs and the preset data files: what is simulated."""
