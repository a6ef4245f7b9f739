"""What is measured on a solution: contact-force statistics and the static stiffness."""
